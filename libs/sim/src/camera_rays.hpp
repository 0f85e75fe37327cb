#pragma once
// Per-pixel rays of a camera fixed on the robot, precomputed once (lens
// distortion included, through core's CameraModel). The robot only moves on
// the ground plane, so per frame a ray changes only by the robot's yaw and
// position: its slope, its floor hit (relative to the robot) and its
// azimuth bin never change.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "ivoa/core/camera_model.hpp"

namespace ivoa::sim::detail {

struct PixelRay {
  float ux = 1, uy = 0;  // unit horizontal direction, robot frame
  float slope = 0;       // rise per metre of horizontal travel
  float inv_slope = 0;
  float len = 1;  // 3-D length per metre of horizontal travel
  float inv_len = 1;
  float planar = 1;                // depth along the optical axis per metre of horizontal travel
  float s_floor = 0;               // horizontal distance to the ground (inf when the ray looks up)
  float floor_x = 0, floor_y = 0;  // ground hit, robot frame
  float floor_footprint = 0;       // metres of ground one pixel covers there
  uint16_t bin = 0;                // azimuth bin (see CameraRays)
};

class CameraRays {
 public:
  // bin_pixels: width of an azimuth bin in pixels at the image centre.
  explicit CameraRays(const CameraModel& camera, double bin_pixels = 2.0);

  int width() const { return width_; }
  int height() const { return height_; }
  const PixelRay& ray(int i) const { return rays_[static_cast<size_t>(i)]; }
  const Eigen::Vector3d& origin() const { return origin_; }  // robot frame
  float pixel_angle() const { return pixel_angle_; }
  // Azimuth bins over [az_min, az_min + num_bins * bin_width) in the robot frame.
  float az_min() const { return az_min_; }
  float bin_width() const { return bin_width_; }
  int num_bins() const { return num_bins_; }

 private:
  int width_, height_;
  Eigen::Vector3d origin_;
  float pixel_angle_;
  float az_min_ = 0, bin_width_ = 0;
  int num_bins_ = 0;
  std::vector<PixelRay> rays_;
};

// Rays are expensive to build (an iterative undistortion per pixel) and the
// same rig is used over and over: shared per camera model in the process.
std::shared_ptr<const CameraRays> shared_camera_rays(const CameraModel& camera);

}  // namespace ivoa::sim::detail
