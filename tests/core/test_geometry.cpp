#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/rectification.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

TEST(Geometry, PointOnOpticalAxisLandsOnPrincipalPoint) {
  const RigCalibration rig = test::make_test_rig(15.0);
  const RigGeometry geo(rig);
  // 2 m along the left camera's optical axis.
  const Eigen::Vector3d p = rig.left_to_robot * Eigen::Vector3d(0, 0, 2.0);
  const auto px = geo.left.project(p);
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), rig.left.K(0, 2), 1e-9);
  EXPECT_NEAR(px->y(), rig.left.K(1, 2), 1e-9);
}

TEST(Geometry, KnownGroundPointLandsOnKnownPixel) {
  // Camera 0.3 m high, pitched 15 deg down, no distortion: a ground point
  // straight ahead at distance d is seen at angle atan(0.3/d) below the
  // horizon, i.e. atan(0.3/d) - 15 deg below the optical axis.
  const RigCalibration rig = test::make_test_rig(15.0);
  const RigGeometry geo(rig);
  const double d = 1.5;
  const auto px = geo.left.project({d, 0.06, 0.0});  // camera is at y = 0.06
  ASSERT_TRUE(px);
  const double below_axis = std::atan(0.30 / d) - 15.0 * M_PI / 180.0;
  EXPECT_NEAR(px->y(), rig.left.K(1, 2) + 600.0 * std::tan(below_axis), 1e-6);
  EXPECT_NEAR(px->x(), rig.left.K(0, 2), 1e-6);
}

TEST(Geometry, ProjectUnprojectRoundTripWithDistortion) {
  const RigCalibration rig = test::make_test_rig(15.0, true);
  const RigGeometry geo(rig);
  int tested = 0;
  for (double x = 0.5; x < 4.0; x += 0.37) {
    for (double y = -1.0; y <= 1.0; y += 0.29) {
      for (double z : {0.0, 0.2, 0.5}) {
        const Eigen::Vector3d p(x, y, z);
        const auto px = geo.left.project(p);
        ASSERT_TRUE(px);
        // The distortion polynomial is only meaningful inside the image.
        if (!geo.left.in_image(*px)) continue;
        ++tested;
        const double depth = geo.left.to_camera(p).z();
        EXPECT_LT((geo.left.unproject(*px, depth) - p).norm(), 1e-6) << p.transpose();
        const Eigen::Vector3d ray = geo.left.ray(*px);
        EXPECT_NEAR(ray.dot((p - geo.left.origin()).normalized()), 1.0, 1e-9);
      }
    }
  }
  EXPECT_GT(tested, 100);
}

TEST(Geometry, PointsBehindTheCameraDoNotProject) {
  const RigGeometry geo(test::make_test_rig());
  EXPECT_FALSE(geo.left.project({-1.0, 0.0, 0.3}));
  EXPECT_FALSE(geo.depth.project({-0.5, 0.0, 0.0}));
}

TEST(Geometry, RightCameraSeesBaselineDisparity) {
  RigCalibration rig = test::make_test_rig(0.0);
  rig.stereo_R.setIdentity();
  rig.stereo_T = {-0.12, 0, 0};
  rig.right.K = rig.left.K;
  const RigGeometry geo(rig);
  const Eigen::Vector3d p = rig.left_to_robot * Eigen::Vector3d(0.1, 0.05, 3.0);
  const auto l = geo.left.project(p), r = geo.right.project(p);
  ASSERT_TRUE(l && r);
  EXPECT_NEAR(l->x() - r->x(), 600.0 * 0.12 / 3.0, 1e-9);
  EXPECT_NEAR(l->y(), r->y(), 1e-9);
}

TEST(Geometry, RectificationKeepsEpipolarRowsAndDisparity) {
  const RigCalibration rig = test::make_test_rig(15.0, true);
  for (double scale : {1.0, 0.5}) {
    const StereoRectification rect(rig, scale);
    EXPECT_EQ(rect.size().width, static_cast<int>(960 * scale));
    EXPECT_NEAR(rect.baseline(), rig.baseline(), 1e-6);
    for (double x = 0.6; x < 4.0; x += 0.5) {
      for (double y = -0.8; y <= 0.8; y += 0.4) {
        Eigen::Vector2d l, r;
        ASSERT_TRUE(rect.project({x, y, 0.1}, l, r));
        EXPECT_NEAR(l.y(), r.y(), 1e-9);
        const double z = rect.to_rectified_camera({x, y, 0.1}).z();
        const double disparity = (l.x() - rect.cx()) - (r.x() - rect.cx_right());
        EXPECT_NEAR(disparity, rect.focal() * rect.baseline() / z, 1e-6);
        EXPECT_LT((rect.unproject(l, l.x() - r.x()) - Eigen::Vector3d(x, y, 0.1)).norm(), 1e-6);
      }
    }
  }
}

TEST(Geometry, RectifiedImagesPutAPointOnOneRow) {
  // Render a bright dot where a 3-D point projects in each raw image, rectify
  // both, and check the dots land on the same row at the predicted columns.
  const RigCalibration rig = test::make_test_rig(15.0, true);
  const RigGeometry geo(rig);
  const StereoRectification rect(rig, 1.0);
  const Eigen::Vector3d p(2.0, 0.3, 0.2);
  cv::Mat left(600, 960, CV_8UC1, cv::Scalar(0)), right = left.clone();
  const auto pl = geo.left.project(p), pr = geo.right.project(p);
  ASSERT_TRUE(pl && pr);
  cv::circle(left, cv::Point(cvRound(pl->x()), cvRound(pl->y())), 2, cv::Scalar(255), -1);
  cv::circle(right, cv::Point(cvRound(pr->x()), cvRound(pr->y())), 2, cv::Scalar(255), -1);
  cv::Mat lr, rr;
  rect.rectify(left, right, lr, rr);
  cv::Point ml, mr;
  cv::minMaxLoc(lr, nullptr, nullptr, nullptr, &ml);
  cv::minMaxLoc(rr, nullptr, nullptr, nullptr, &mr);
  Eigen::Vector2d el, er;
  ASSERT_TRUE(rect.project(p, el, er));
  EXPECT_NEAR(ml.y, mr.y, 1.0);
  EXPECT_NEAR(ml.x, el.x(), 1.5);
  EXPECT_NEAR(mr.x, er.x(), 1.5);
  EXPECT_NEAR(ml.y, el.y(), 1.5);
}

}  // namespace
}  // namespace ivoa
