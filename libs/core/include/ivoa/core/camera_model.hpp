#pragma once
// Projection between the robot frame and the pixels of the rig's cameras.
#include <optional>

#include <Eigen/Core>

#include "ivoa/core/calibration.hpp"

namespace ivoa {

// Points closer than this along the optical axis do not project (behind or
// inside the camera), metres.
inline constexpr double kMinProjectionDepth = 0.05;

// Pinhole camera with OpenCV plumb-bob distortion, placed in the robot frame.
class CameraModel {
 public:
  CameraModel(const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& camera_to_robot);

  // Robot point -> pixel of the raw image (distortion applied).
  // Empty if the point is behind the camera; may lie outside the image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_robot) const;
  // Pixel of the raw image and depth along the optical axis -> robot point.
  Eigen::Vector3d unproject(const Eigen::Vector2d& pixel, double depth) const;
  // Unit ray (robot frame) through a raw pixel.
  Eigen::Vector3d ray(const Eigen::Vector2d& pixel) const;

  Eigen::Vector3d to_camera(const Eigen::Vector3d& p_robot) const { return robot_to_camera_ * p_robot; }
  Eigen::Vector3d origin() const { return camera_to_robot_.translation(); }
  bool in_image(const Eigen::Vector2d& pixel, double margin = 0.0) const;
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }

 private:
  Eigen::Vector2d distort(const Eigen::Vector2d& normalized) const;
  Eigen::Vector2d undistort(const Eigen::Vector2d& pixel) const;

  CameraIntrinsics intrinsics_;
  Eigen::Isometry3d camera_to_robot_;
  Eigen::Isometry3d robot_to_camera_;
  bool has_distortion_;
};

// The three cameras of a rig.
struct RigGeometry {
  explicit RigGeometry(const RigCalibration& rig);
  RigCalibration calibration;
  CameraModel left;
  CameraModel right;
  CameraModel depth;
};

}  // namespace ivoa
