#include "ivoa/openni2_kinect/depth_intrinsics.hpp"

#include <cmath>
#include <stdexcept>

#include "ivoa/core/calibration.hpp"

namespace ivoa::openni2_kinect {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

PinholeIntrinsics intrinsics_from_fov(int width, int height, double hfov_rad, double vfov_rad) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("image size must be positive");
  if (!(hfov_rad > 0 && hfov_rad < kPi && vfov_rad > 0 && vfov_rad < kPi))
    throw std::invalid_argument("field of view must be in (0, pi) radians, got " + std::to_string(hfov_rad) + " x " +
                                std::to_string(vfov_rad));
  PinholeIntrinsics k;
  k.fx = 0.5 * width / std::tan(0.5 * hfov_rad);
  k.fy = 0.5 * height / std::tan(0.5 * vfov_rad);
  k.cx = 0.5 * width;
  k.cy = 0.5 * height;
  // The focal lengths a calibration file may give (calibration.hpp).
  if (!(k.fx >= kMinFocalPx && k.fx <= kMaxFocalPx && k.fy >= kMinFocalPx && k.fy <= kMaxFocalPx))
    throw std::invalid_argument("a field of view of " + std::to_string(hfov_rad) + " x " + std::to_string(vfov_rad) +
                                " radians makes focal lengths of " + std::to_string(k.fx) + " x " +
                                std::to_string(k.fy) + " px, no lens's");
  return k;
}

PinholeIntrinsics intrinsics_from_rig(const RigCalibration& rig, int width, int height, const std::string& rig_path) {
  const CameraIntrinsics& depth = rig.depth;
  if (depth.width != width || depth.height != height)
    throw CalibrationError(rig_path + ": depth sensor calibrated for " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + " (depth_width/depth_height) but the device streams " +
                           std::to_string(width) + "x" + std::to_string(height));
  PinholeIntrinsics k;
  k.fx = depth.K(0, 0);
  k.fy = depth.K(1, 1);
  k.cx = depth.K(0, 2);
  k.cy = depth.K(1, 2);
  return k;
}

}  // namespace ivoa::openni2_kinect
