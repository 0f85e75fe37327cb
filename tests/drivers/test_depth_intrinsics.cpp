// Field of view -> pinhole intrinsics (OpenNI2's model), and the rig file's
// depth intrinsics, for the Kinect driver.
#include <gtest/gtest.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/openni2_kinect/depth_intrinsics.hpp"
#include "ivoa/openni2_kinect/frame_buffer.hpp"

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
  // A damaged recording's 1e-30 rad: fx 6.4e32 px was published.
  EXPECT_THROW(intrinsics_from_fov(640, 480, 1e-30, 0.8), std::invalid_argument);
}

// A damaged recording claimed a mode larger than its frames: the driver
// wrapped the buffer as that image and read past its end (SIGSEGV).
TEST(FrameBuffer, AFrameIsReadOnlyFromDataThatHoldsIt) {
  EXPECT_EQ(frame_buffer_error(640, 480, 1280, 2, 640 * 480 * 2), "");
  EXPECT_EQ(frame_buffer_error(640, 480, 1280, 2, 640 * 480 * 2 - 1),
            "640x480 frame in 614399 bytes of data, not the 614400 it needs");
  EXPECT_EQ(frame_buffer_error(1280, 480, 2560, 2, 640 * 480 * 2),
            "1280x480 frame in 614400 bytes of data, not the 1228800 it needs");
  EXPECT_EQ(frame_buffer_error(640, 480, 640, 2, 1 << 30),
            "640x480 frame with rows 640 bytes apart, too close for 1280 bytes a row");
  EXPECT_EQ(frame_buffer_error(0, 480, 0, 2, 100), "a 0x480 frame");
  EXPECT_NE(frame_buffer_error(100000, 100000, 200000, 2, 1 << 30).find("larger than any image"), std::string::npos);
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
