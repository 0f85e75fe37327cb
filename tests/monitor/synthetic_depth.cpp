#include "synthetic_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ivoa::test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Ray p(t) = o + t d against an axis-aligned box: entry/exit parameters.
bool slab(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
          double& t_in, double& t_out) {
  t_in = -kInf;
  t_out = kInf;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out && t_out > 0;
}

double hit(const DepthScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = kInf;
  for (const Box& b : scene.boxes) {
    double tin, tout;
    if (slab(o, d, {b.x0, b.y0, 0}, {b.x1, b.y1, b.height}, tin, tout) && tin > 0) best = std::min(best, tin);
  }
  if (d.z() < 0) {
    const double t_ground = -o.z() / d.z();
    if (t_ground < best) {
      const Eigen::Vector3d g = o + t_ground * d;
      const Pit* pit = nullptr;
      for (const Pit& p : scene.pits)
        if (g.x() > p.x0 && g.x() < p.x1 && g.y() > p.y0 && g.y() < p.y1) pit = &p;
      if (!pit) return t_ground;
      double tin, tout;  // inside the pit: the far wall or the bottom
      slab(o, d, {pit->x0, pit->y0, -pit->depth}, {pit->x1, pit->y1, 0}, tin, tout);
      best = std::min(best, tout);
    }
  }
  return best;
}

}  // namespace

cv::Mat render_depth(const RigCalibration& rig, const DepthScene& scene) {
  const CameraModel camera(rig.depth, rig.depth_to_robot);
  const Eigen::Vector3d o = camera.origin();
  std::mt19937 rng(scene.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  cv::Mat depth(rig.depth.height, rig.depth.width, CV_16UC1, cv::Scalar(0));
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const Eigen::Vector3d dir = camera.unproject({u, v}, 1.0) - o;  // planar depth 1 m
      const double t = hit(scene, o, dir);                            // = planar depth
      if (!std::isfinite(t)) continue;
      const double z = t + scene.noise_coefficient * t * t * unit(rng);
      if (z < rig.depth_min_range || z > rig.depth_max_range) continue;
      depth.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(z * 1000.0));
    }
  }
  return depth;
}

double distance_to_nearest_obstacle(const DepthScene& scene, double x, double y) {
  auto rect_distance = [&](double x0, double x1, double y0, double y1) {
    const double dx = std::max({x0 - x, 0.0, x - x1}), dy = std::max({y0 - y, 0.0, y - y1});
    return std::hypot(dx, dy);
  };
  double best = kInf;
  for (const Box& b : scene.boxes) best = std::min(best, rect_distance(b.x0, b.x1, b.y0, b.y1));
  for (const Pit& p : scene.pits) best = std::min(best, rect_distance(p.x0, p.x1, p.y0, p.y1));
  return best;
}

}  // namespace ivoa::test
