#pragma once
// The ground query grid: points (x, y, 0) in front of the robot where both
// the stereo detector and the depth monitor answer "is the footprint of
// radius r around this point free?". Each cell knows its pixel in the raw
// left image and whether the introspection patch around it is fully inside.
#include <vector>

#include <opencv2/core/types.hpp>

#include "ivoa/core/camera_model.hpp"

namespace ivoa {

// What the command-line options accept (defaults: 143 cells, 0.1 m).
inline constexpr double kMaxQueryCells = 10000;
inline constexpr double kMaxSafetyRadiusM = 1.0;
// Grid bounds lie within this many metres of the robot (no sensor sees farther).
inline constexpr double kMaxGridExtentM = 100.0;

struct QueryGridConfig {
  double x_min = 0.5;           // metres ahead of the robot origin
  double x_max = 3.0;           // metres
  double y_min = -1.5;          // metres (right is negative)
  double y_max = 1.5;           // metres
  double spacing = 0.25;        // metres between grid points
  double safety_radius = 0.10;  // metres, r in the IVOA paper
  int patch_size = 100;         // pixels, introspection patch side
};

struct QueryCell {
  double x = 0, y = 0;    // robot frame, metres (z = 0)
  double u = 0, v = 0;    // raw left image pixel (NaN when behind the camera)
  bool projects = false;  // in front of the left camera
  bool in_image = false;  // the whole patch lies inside the left image
};

class QueryGrid {
 public:
  QueryGrid(const QueryGridConfig& config, const CameraModel& left_camera);

  const QueryGridConfig& config() const { return config_; }
  int num_x() const { return num_x_; }
  int num_y() const { return num_y_; }
  int size() const { return static_cast<int>(cells_.size()); }
  const QueryCell& cell(int i) const { return cells_[static_cast<size_t>(i)]; }
  const std::vector<QueryCell>& cells() const { return cells_; }
  int index(int ix, int iy) const { return ix * num_y_ + iy; }
  int count_in_image() const;

 private:
  QueryGridConfig config_;
  int num_x_ = 0, num_y_ = 0;
  std::vector<QueryCell> cells_;
};

// Number of grid points in [lo, hi] at `step`, counted with integers so that
// float accumulation can never drop or add the last point.
int grid_count(double lo, double hi, double step);

// The patch_size x patch_size square centred on pixel (u, v), as used for
// training samples and heatmap lookups.
cv::Rect patch_rect(double u, double v, int patch_size);

}  // namespace ivoa
