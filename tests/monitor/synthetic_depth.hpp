#pragma once
// An analytic depth renderer for monitor tests, independent of the
// simulator: a ground plane with axis-aligned boxes standing on it and
// rectangular pits cut into it, seen by the rig's depth sensor.
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/camera_model.hpp"

namespace ivoa::test {

struct Box {  // robot frame, metres
  double x0, x1, y0, y1, height;
};
struct Pit {
  double x0, x1, y0, y1, depth;
};

struct DepthScene {
  std::vector<Box> boxes;
  std::vector<Pit> pits;
  double noise_coefficient = 1.4e-3;  // sigma = k * z^2 (Kinect-like), 0 = exact
  unsigned seed = 1;
};

cv::Mat render_depth(const RigCalibration& rig, const DepthScene& scene);

// Truth for a cell: an obstacle (box higher than min_height, or a pit)
// within r of (x, y); distance from (x, y) to the nearest such footprint.
double distance_to_nearest_obstacle(const DepthScene& scene, double x, double y);

}  // namespace ivoa::test
