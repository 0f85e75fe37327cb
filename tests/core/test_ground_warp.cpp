// The ground warp samples the right image exactly where the ground point
// under a left pixel projects, and a flat textured ground warps onto the
// left view while anything standing up does not.
#include <gtest/gtest.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

TEST(GroundWarp, GroundPointsMapToTheirRightPixel) {
  const RigCalibration rig = test::make_test_rig(15.0, true);
  const RigGeometry geo(rig);
  const GroundWarp warp(rig);
  int tested = 0;
  for (double x = 0.6; x < 4.0; x += 0.45)
    for (double y = -1.0; y <= 1.0; y += 0.4) {
      const auto l = geo.left.project({x, y, 0.0});
      const auto r = geo.right.project({x, y, 0.0});
      ASSERT_TRUE(l && r);
      if (!geo.left.in_image(*l, 2)) continue;
      // Integer left pixel: move the ground point to the ray through it.
      const int u = static_cast<int>(std::lround(l->x())), v = static_cast<int>(std::lround(l->y()));
      const Eigen::Vector3d ray = geo.left.ray({u, v}), o = geo.left.origin();
      const Eigen::Vector3d ground = o + (-o.z() / ray.z()) * ray;
      const auto expected = geo.right.project(ground);
      ASSERT_TRUE(expected);
      const cv::Point2f got = warp.source(u, v);
      EXPECT_NEAR(got.x, expected->x(), 1e-3) << x << " " << y;
      EXPECT_NEAR(got.y, expected->y(), 1e-3) << x << " " << y;
      ++tested;
    }
  EXPECT_GT(tested, 20);
}

TEST(GroundWarp, RaisedPointsAreOffTheirRightPixel) {
  // A point 0.4 m above the ground is seen by the left camera in front of
  // the ground point the warp assumes: its right pixel is elsewhere.
  const RigCalibration rig = test::make_test_rig(15.0);
  const RigGeometry geo(rig);
  const GroundWarp warp(rig);
  const auto l = geo.left.project({1.5, 0.2, 0.4});
  const auto r = geo.right.project({1.5, 0.2, 0.4});
  ASSERT_TRUE(l && r);
  const cv::Point2f got = warp.source(static_cast<int>(std::lround(l->x())), static_cast<int>(std::lround(l->y())));
  EXPECT_GT(std::abs(got.x - r->x()), 5.0);
}

TEST(GroundWarp, WarpedImageHasTheLeftSizeAndBlackOutsideTheRightView) {
  const RigCalibration rig = test::make_test_rig(15.0);
  const GroundWarp warp(rig);
  cv::Mat right(rig.right.height, rig.right.width, CV_8UC3, cv::Scalar(40, 120, 200));
  const cv::Mat out = warp.warp(right);
  ASSERT_EQ(out.size(), cv::Size(rig.left.width, rig.left.height));
  EXPECT_EQ(out.type(), CV_8UC3);
  // Near the left camera, low down at its left edge, the ground lies
  // outside the right camera's view (0.12 m to the right): black there,
  // the right image's colour where it is well inside.
  int inside = 0, outside = 0;
  for (int v = 0; v < out.rows; v += 7)
    for (int u = 0; u < out.cols; u += 7) {
      const cv::Point2f src = warp.source(u, v);
      const cv::Vec3b got = out.at<cv::Vec3b>(v, u);
      if (src.x > 2 && src.x < rig.right.width - 3 && src.y > 2 && src.y < rig.right.height - 3) {
        ++inside;
        EXPECT_EQ(got, cv::Vec3b(40, 120, 200)) << u << "," << v;
      } else if (src.x < -2 || src.x > rig.right.width + 1 || src.y < -2 || src.y > rig.right.height + 1) {
        ++outside;
        EXPECT_EQ(got, cv::Vec3b(0, 0, 0)) << u << "," << v;
      }
    }
  EXPECT_GT(inside, 5000);
  EXPECT_GT(outside, 10);
  EXPECT_THROW(warp.warp(cv::Mat(10, 10, CV_8UC3)), cv::Exception);
}

}  // namespace
}  // namespace ivoa
