// Field of view -> pinhole intrinsics (OpenNI2's model), and the rig file's
// depth intrinsics, for the Kinect driver.
#include <gtest/gtest.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/openni2_kinect/depth_intrinsics.hpp"

namespace ivoa::openni2_kinect {
namespace {

TEST(DepthIntrinsics, KinectV1DepthFieldOfView) {
  const PinholeIntrinsics k = intrinsics_from_fov(640, 480, kKinectV1DepthHfovRad, kKinectV1DepthVfovRad);
  EXPECT_NEAR(k.fx, 571.4, 0.5);
  EXPECT_NEAR(k.fy, 570.9, 0.5);
  EXPECT_DOUBLE_EQ(k.cx, 320.0);
  EXPECT_DOUBLE_EQ(k.cy, 240.0);
}

TEST(DepthIntrinsics, KinectV1ColourFieldOfView) {
  const PinholeIntrinsics k = intrinsics_from_fov(640, 480, 1.0821, 0.8482);
  EXPECT_NEAR(k.fx, 532.6, 0.5);
  EXPECT_NEAR(k.fy, 531.5, 0.5);
}

TEST(DepthIntrinsics, ProjectsTheFieldOfViewEdgeToTheImageEdge) {
  const double hfov = 1.2;
  const PinholeIntrinsics k = intrinsics_from_fov(320, 240, hfov, 0.9);
  EXPECT_NEAR(k.cx + k.fx * std::tan(hfov / 2), 320.0, 1e-9);
}

TEST(DepthIntrinsics, RejectsAMissingFieldOfView) {
  EXPECT_THROW(intrinsics_from_fov(640, 480, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(intrinsics_from_fov(640, 480, 4.0, 0.8), std::invalid_argument);
  EXPECT_THROW(intrinsics_from_fov(0, 480, 1.0, 0.8), std::invalid_argument);
}

TEST(DepthIntrinsics, FromTheRigWhenItMatchesTheStream) {
  RigCalibration rig;
  rig.depth.width = 640;
  rig.depth.height = 480;
  rig.depth.K << 580, 0, 318.5, 0, 581, 242.25, 0, 0, 1;
  const PinholeIntrinsics k = intrinsics_from_rig(rig, 640, 480, "rig.yaml");
  EXPECT_EQ(k.fx, 580);
  EXPECT_EQ(k.fy, 581);
  EXPECT_EQ(k.cx, 318.5);
  EXPECT_EQ(k.cy, 242.25);
  try {
    intrinsics_from_rig(rig, 320, 240, "rig.yaml");
    FAIL() << "a size mismatch must be refused";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("320x240"), std::string::npos);
  }
}

}  // namespace
}  // namespace ivoa::openni2_kinect
