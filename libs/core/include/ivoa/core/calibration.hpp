#pragma once
// The rig calibration: both stereo cameras, the depth sensor and where they
// sit on the robot. One file format (OpenCV FileStorage YAML, key names as in
// JPP's calibration files where they exist) and conversions to and from the
// ivoa.rig_calibration_t message.
//
// Frames: robot x forward, y left, z up, ground z = 0, metres. Camera frames
// are optical (x right, y down, z forward) for the raw, unrectified image.
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace ivoa {
class rig_calibration_t;

struct CameraIntrinsics {
  std::string name;
  int width = 0;                                    // pixels
  int height = 0;                                   // pixels
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // pixels
  std::array<double, 5> D{};                        // k1, k2, p1, p2, k3
};

struct RigCalibration {
  std::string rig_name;
  CameraIntrinsics left;
  CameraIntrinsics right;
  Eigen::Matrix3d stereo_R = Eigen::Matrix3d::Identity();  // p_right = R p_left + T
  Eigen::Vector3d stereo_T = Eigen::Vector3d::Zero();      // metres
  Eigen::Isometry3d left_to_robot = Eigen::Isometry3d::Identity();
  CameraIntrinsics depth;
  Eigen::Isometry3d depth_to_robot = Eigen::Isometry3d::Identity();
  double depth_min_range = 0.5;  // metres
  double depth_max_range = 4.5;  // metres

  double baseline() const { return stereo_T.norm(); }
};

// Thrown for a calibration that cannot be used; what() names the file or
// message and the offending key.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Rotation of an optical frame into the robot frame for a camera looking
// forward along robot x, pitched down by `pitch_down_rad` about robot y.
Eigen::Matrix3d optical_to_robot(double pitch_down_rad);

// The focal lengths a camera may have, in pixels: outside them OpenCV's
// undistortion and the renderer fail (an fx of 1e-9 crashed the renderer).
constexpr double kMinFocalPx = 1, kMaxFocalPx = 1e6;
// The stereo baseline and how far a camera may sit from the robot's origin,
// in metres: past them no robot is described.
constexpr double kMaxBaselineM = 10, kMaxMountM = 100;

// Checks sizes, focal lengths, rotations and ranges; throws CalibrationError
// naming `where` and the first problem found.
void validate(const RigCalibration& rig, const std::string& where);

RigCalibration load_rig_calibration(const std::string& path);
void save_rig_calibration(const RigCalibration& rig, const std::string& path);

rig_calibration_t to_message(const RigCalibration& rig, int64_t utime);
RigCalibration from_message(const rig_calibration_t& msg);  // validates

// Tells a new calibration from the same one re-published (every second) by
// its content, the publication time left out.
class CalibrationChanges {
 public:
  // The rig of `msg` if its content is not the last one taken, else empty.
  // Throws CalibrationError for an invalid one, which is not taken: each
  // re-publication of it is checked, and reported, again.
  std::optional<RigCalibration> take_if_new(const rig_calibration_t& msg);
  // Takes a rig from elsewhere (a calibration file), as if it had come.
  void take(const RigCalibration& rig);

 private:
  std::vector<uint8_t> content_;
};

}  // namespace ivoa
