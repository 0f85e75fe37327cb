#include "ivoa/sim/sim_rig.hpp"

#include <cmath>

namespace ivoa::sim {
namespace {

CameraIntrinsics camera(const std::string& name, int w, int h, double f, double dcx, double dcy) {
  CameraIntrinsics c;
  c.name = name;
  c.width = w;
  c.height = h;
  c.K << f, 0, (w - 1) / 2.0 + dcx, 0, f * 1.0008, (h - 1) / 2.0 + dcy, 0, 0, 1;
  return c;
}

}  // namespace

RigCalibration make_sim_rig(const SimRigParams& p) {
  RigCalibration rig;
  rig.rig_name = "ivoa_sim";
  // Two real lenses are never identical: slightly different focal lengths,
  // principal points and distortion, and a small relative rotation.
  rig.left = camera("left", 960, 600, p.focal, 1.8, -2.3);
  rig.right = camera("right", 960, 600, p.focal * 1.004, -1.2, 1.6);
  if (p.distortion) {
    rig.left.D = {-0.090, 0.035, 0.0004, -0.0003, 0.0};
    rig.right.D = {-0.086, 0.031, -0.0002, 0.0004, 0.0};
  }
  rig.stereo_R =
      (Eigen::AngleAxisd(0.0025, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.0015, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(0.001, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  rig.stereo_T = Eigen::Vector3d(-p.baseline, 0.0006, 0.0011);
  const double pitch = p.pitch_deg * M_PI / 180.0;
  rig.left_to_robot.linear() = optical_to_robot(pitch);
  rig.left_to_robot.translation() = Eigen::Vector3d(0.05, p.baseline / 2, p.camera_height);
  rig.depth = camera("depth", 640, 480, 570.0, 0.0, 0.0);
  rig.depth.K(1, 1) = 570.0;
  rig.depth_to_robot.linear() = optical_to_robot(p.depth_pitch_deg * M_PI / 180.0);
  rig.depth_to_robot.translation() = Eigen::Vector3d(0.03, 0.0, p.camera_height + p.depth_above);
  rig.depth_min_range = 0.5;
  rig.depth_max_range = 4.5;
  validate(rig, "make_sim_rig");
  return rig;
}

}  // namespace ivoa::sim
