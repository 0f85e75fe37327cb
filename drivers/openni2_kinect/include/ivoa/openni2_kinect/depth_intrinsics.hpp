#pragma once
// Pinhole intrinsics of the depth image: from the sensor's field of view
// (what OpenNI2 reports) or from the rig calibration file.
#include <string>

namespace ivoa {
struct RigCalibration;
}

namespace ivoa::openni2_kinect {

struct PinholeIntrinsics {
  double fx = 0, fy = 0;  // pixels
  double cx = 0, cy = 0;  // pixels
};

// OpenNI2's own model (CoordinateConverter): fx = (W/2) / tan(hfov/2),
// fy = (H/2) / tan(vfov/2), principal point at (W/2, H/2). Kinect v1 depth
// (58.5 x 45.6 deg) at 640x480 gives fx ~ 571.4, fy ~ 570.9. Throws
// std::invalid_argument for a size or field of view that is not positive.
PinholeIntrinsics intrinsics_from_fov(int width, int height, double hfov_rad, double vfov_rad);

// K_depth of the rig, which must be calibrated for width x height. Throws
// CalibrationError naming `rig_path` otherwise.
PinholeIntrinsics intrinsics_from_rig(const RigCalibration& rig, int width, int height, const std::string& rig_path);

// Kinect v1 depth camera field of view (libfreenect's OpenNI2 driver), for
// devices that report none.
inline constexpr double kKinectV1DepthHfovRad = 1.0210;
inline constexpr double kKinectV1DepthVfovRad = 0.7959;

}  // namespace ivoa::openni2_kinect
