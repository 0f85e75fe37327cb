#pragma once
// The depth monitor: the supervisor whose verdicts become training labels.
// For every ground query cell it decides, from one depth image, whether the
// robot's footprint of radius r around the ground point is obstacle-free.
//
// Two kinds of evidence per cell (the footprint disc of radius r):
//  * points: depth pixels -> PCL point cloud in the robot frame (range and
//    region filtered) -> voxel grid (so counts measure surface area, not
//    pixel density, which grows near the sensor) -> the points whose
//    horizontal distance to the cell is within r;
//  * ground samples: 13 ground points spread over the disc, each looked up
//    along its own sensor ray. What the ray actually hit tells whether that
//    spot of ground is seen (a hit at ground height, at the spot itself),
//    hidden (a hit short of it: possibly the foot of an object standing on
//    it), or missing (the ray went below the ground: a pit).
// Near the disc's edge a point's horizontal position is only known to about
// voxel_size / 2 + 3 sigma of the sensor noise at its range, so points in
// that band around r are "edge" evidence: they can neither make an
// OBSTACLE nor allow a FREE.
// Verdict:
//   OBSTACLE  >= min_obstacle_points points inside the band stand higher than
//             obstacle_min_height (below obstacle_max_height), or
//             >= min_hole_points points lie deeper than hole_min_depth
//             below the ground, or >= min_hole_samples sample rays passed
//             through where the ground should be;
//   UNKNOWN   if that many obstacle or hole points exist only when the edge
//             band is counted too (an obstacle right at r: too close to call);
//   FREE      no such evidence, and the ground is seen at >= min_seen_fraction
//             of the samples and hidden at none (a hidden spot could hold an
//             obstacle whose visible faces lie outside the disc);
//   UNKNOWN   otherwise: outside the sensor's view or range, occluded, or too
//             few valid returns. Such cells get no training label.
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/query_grid.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::monitor {

struct DepthMonitorConfig {
  int pixel_step = 2;                       // use every n-th depth pixel in each direction
  double voxel_size = 0.02;                 // m, voxel grid leaf size
  double obstacle_min_height = 0.05;        // m above the ground: higher points are obstacle points
  double obstacle_max_height = 1.0;         // m: higher points cannot hit the robot (overhangs ignored)
  double hole_min_depth = 0.05;             // m below the ground: deeper points are hole points
  int min_obstacle_points = 3;              // obstacle voxels within r for OBSTACLE (~12 cm^2 of surface)
  int min_hole_points = 3;                  // hole voxels within r for OBSTACLE (negative obstacle)
  int min_hole_samples = 2;                 // sample rays through the ground for OBSTACLE (negative obstacle)
  double min_seen_fraction = 0.8;           // of the 13 ground samples, seen for FREE
  double ground_match_tolerance = 0.03;     // m, how far a ground hit may land from its sample ...
  double depth_noise_coefficient = 1.4e-3;  // ... plus 3 sigma of the sensor noise, sigma = k * range^2 (1/m)
};

// Evidence behind one cell's verdict (for diagnostics and the viewer).
struct CellEvidence {
  int obstacle_points = 0;       // voxels within r (inside the edge band) above the ground
  int hole_points = 0;           // ... below the ground
  int edge_obstacle_points = 0;  // voxels in the edge band around r above the ground
  int edge_hole_points = 0;      // ... below the ground
  int samples_seen = 0;          // ground samples whose ray hit ground height
  int samples_hidden = 0;        // ... hit something tall first
  int samples_holes = 0;         // ... went below the ground
  int samples_total = 0;
};

class DepthMonitor {
 public:
  DepthMonitor(const RigCalibration& rig, DepthMonitorConfig config = {});
  ~DepthMonitor();
  DepthMonitor(DepthMonitor&&) noexcept;
  DepthMonitor& operator=(DepthMonitor&&) noexcept;

  // Fills out.state for every cell of `grid` from a CV_16UC1 depth image in
  // millimetres (0 = invalid). Throws ImageError naming the problem if the
  // image is not CV_16UC1 of the calibrated depth sensor size.
  void evaluate(const cv::Mat& depth_mm, const QueryGrid& grid, obstacle_grid_t& out,
                std::vector<CellEvidence>* evidence = nullptr) const;

  const DepthMonitorConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ivoa::monitor
