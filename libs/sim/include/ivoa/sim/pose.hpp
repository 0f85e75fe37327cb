#pragma once
// Robot pose and velocity on the ground plane of a simulated scene.
#include <cmath>

#include <Eigen/Geometry>

namespace ivoa::sim {

// Robot in the scene's world frame: metres, radians (yaw about +z, 0 = +x).
struct Pose2D {
  double x = 0, y = 0, yaw = 0;
};

// Body velocity: forward speed (m/s) and yaw rate (rad/s).
struct Twist2D {
  double v = 0, omega = 0;
};

// World point of a robot-frame ground point (x forward, y left).
inline Eigen::Vector2d robot_to_world(const Pose2D& pose, double x, double y) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {pose.x + c * x - s * y, pose.y + s * x + c * y};
}

// Robot frame -> world frame as a 3-D isometry (z unchanged: the ground is z = 0 in both).
inline Eigen::Isometry3d robot_to_world(const Pose2D& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(pose.x, pose.y, 0.0);
  return t;
}

}  // namespace ivoa::sim
