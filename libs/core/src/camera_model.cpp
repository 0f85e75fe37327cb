#include "ivoa/core/camera_model.hpp"

#include <cmath>
#include <limits>

namespace ivoa {

CameraModel::CameraModel(const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& camera_to_robot)
    : intrinsics_(intrinsics),
      camera_to_robot_(camera_to_robot),
      robot_to_camera_(camera_to_robot.inverse()),
      has_distortion_(false) {
  for (double d : intrinsics.D) has_distortion_ = has_distortion_ || d != 0.0;
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& n) const {
  if (!has_distortion_) return n;
  const auto& D = intrinsics_.D;
  const double x = n.x(), y = n.y(), r2 = x * x + y * y;
  const double radial = 1 + r2 * (D[0] + r2 * (D[1] + r2 * D[4]));
  return {x * radial + 2 * D[2] * x * y + D[3] * (r2 + 2 * x * x),
          y * radial + D[2] * (r2 + 2 * y * y) + 2 * D[3] * x * y};
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d& pixel) const {
  const Eigen::Matrix3d& K = intrinsics_.K;
  const double y0 = (pixel.y() - K(1, 2)) / K(1, 1);
  const double x0 = (pixel.x() - K(0, 2) - K(0, 1) * y0) / K(0, 0);
  Eigen::Vector2d target(x0, y0), n = target;
  if (!has_distortion_) return n;
  // Fixed-point iteration, as cv::undistortPoints does; converges for the
  // moderate distortion of real lenses.
  for (int i = 0; i < 20; ++i) n += target - distort(n);
  return n;
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p_robot) const {
  const Eigen::Vector3d p = robot_to_camera_ * p_robot;
  if (p.z() < kMinProjectionDepth) return std::nullopt;
  const Eigen::Vector2d d = distort({p.x() / p.z(), p.y() / p.z()});
  const Eigen::Matrix3d& K = intrinsics_.K;
  return Eigen::Vector2d(K(0, 0) * d.x() + K(0, 1) * d.y() + K(0, 2), K(1, 1) * d.y() + K(1, 2));
}

Eigen::Vector3d CameraModel::unproject(const Eigen::Vector2d& pixel, double depth) const {
  const Eigen::Vector2d n = undistort(pixel);
  return camera_to_robot_ * Eigen::Vector3d(n.x() * depth, n.y() * depth, depth);
}

Eigen::Vector3d CameraModel::ray(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d n = undistort(pixel);
  return (camera_to_robot_.linear() * Eigen::Vector3d(n.x(), n.y(), 1.0)).normalized();
}

bool CameraModel::in_image(const Eigen::Vector2d& pixel, double margin) const {
  return pixel.x() >= margin && pixel.y() >= margin && pixel.x() < intrinsics_.width - margin &&
         pixel.y() < intrinsics_.height - margin;
}

RigGeometry::RigGeometry(const RigCalibration& rig)
    : calibration(rig),
      left(rig.left, rig.left_to_robot),
      right(rig.right,
            [&] {
              // right -> robot = (left -> robot) * (right -> left)
              Eigen::Isometry3d left_to_right = Eigen::Isometry3d::Identity();
              left_to_right.linear() = rig.stereo_R;
              left_to_right.translation() = rig.stereo_T;
              return Eigen::Isometry3d(rig.left_to_robot * left_to_right.inverse());
            }()),
      depth(rig.depth, rig.depth_to_robot) {}

}  // namespace ivoa
