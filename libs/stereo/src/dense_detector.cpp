#include "ivoa/stereo/dense_detector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace ivoa::stereo {
namespace {

// Ground bins are this wide; a footprint check reads the bins its disc touches.
constexpr double kBinSize = 0.1;

}  // namespace

DenseDetector::DenseDetector(const RigCalibration& rig, const DenseConfig& config)
    : rig_(rig), config_(config), rect_(rig, config.sgbm.rect_scale), sgbm_(config.sgbm) {
  validate(config_);
  const auto& sgbm = config_.sgbm;
  if (std::abs(sgbm.min_disparity) + sgbm.num_disparities >= rect_.size().width)
    throw std::invalid_argument("stereo detector config: sgbm_min_disparity " + std::to_string(sgbm.min_disparity) +
                                " + sgbm_num_disparities " + std::to_string(sgbm.num_disparities) +
                                " do not fit the rectified image, " + std::to_string(rect_.size().width) +
                                " px wide (lower sgbm_num_disparities or raise sgbm_rect_scale)");
  bins_per_side_ = static_cast<int>(std::ceil(2.0 * config_.max_range / kBinSize));
}

int DenseDetector::bin_of(double x, double y) const {
  const int ix = static_cast<int>(std::floor((x + config_.max_range) / kBinSize));
  const int iy = static_cast<int>(std::floor((y + config_.max_range) / kBinSize));
  if (ix < 0 || iy < 0 || ix >= bins_per_side_ || iy >= bins_per_side_) return -1;
  return ix * bins_per_side_ + iy;
}

void DenseDetector::set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) {
  points_.clear();
  bin_start_.assign(static_cast<size_t>(bins_per_side_) * static_cast<size_t>(bins_per_side_) + 1, 0);
  to_gray_checked(left_raw, right_raw, rig_, left_gray_, right_gray_);
  rect_.rectify(left_gray_, right_gray_, left_rect_, right_rect_);
  disparity_ = sgbm_.compute(left_rect_, right_rect_);
  build_point_bins();
}

void DenseDetector::build_point_bins() {
  // Unproject every valid disparity (rectified left camera -> robot frame),
  // then counting-sort the points by ground bin.
  const Eigen::Isometry3d& to_robot = rect_.rectified_camera_to_robot();
  const double f = rect_.focal(), fb = f * rect_.baseline(), offset = rect_.cx_right() - rect_.cx();
  std::vector<Point> unsorted;
  std::vector<int> bins;
  unsorted.reserve(static_cast<size_t>(disparity_.total()));
  bins.reserve(static_cast<size_t>(disparity_.total()));
  for (int v = 0; v < disparity_.rows; ++v) {
    const float* d = disparity_.ptr<float>(v);
    for (int u = 0; u < disparity_.cols; ++u) {
      const double disparity = static_cast<double>(d[u]) + offset;
      if (!(disparity > 0)) continue;  // NaN or at infinity
      const double z = fb / disparity;
      const Eigen::Vector3d p = to_robot * Eigen::Vector3d((u - rect_.cx()) * z / f, (v - rect_.cy()) * z / f, z);
      const int bin = bin_of(p.x(), p.y());
      if (bin < 0) continue;
      unsorted.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
      bins.push_back(bin);
      ++bin_start_[static_cast<size_t>(bin) + 1];
    }
  }
  for (size_t b = 1; b < bin_start_.size(); ++b) bin_start_[b] += bin_start_[b - 1];
  std::vector<int> next(bin_start_.begin(), bin_start_.end() - 1);
  points_.resize(unsorted.size());
  for (size_t i = 0; i < unsorted.size(); ++i)
    points_[static_cast<size_t>(next[static_cast<size_t>(bins[i])]++)] = unsorted[i];
}

DenseDetector::Counts DenseDetector::count_points(double x, double y, double radius) const {
  Counts counts;
  if (bin_start_.empty()) return counts;
  const int ix_lo = static_cast<int>(std::floor((x - radius + config_.max_range) / kBinSize));
  const int ix_hi = static_cast<int>(std::floor((x + radius + config_.max_range) / kBinSize));
  const int iy_lo = static_cast<int>(std::floor((y - radius + config_.max_range) / kBinSize));
  const int iy_hi = static_cast<int>(std::floor((y + radius + config_.max_range) / kBinSize));
  const double r2 = radius * radius;
  for (int ix = std::max(ix_lo, 0); ix <= std::min(ix_hi, bins_per_side_ - 1); ++ix) {
    for (int iy = std::max(iy_lo, 0); iy <= std::min(iy_hi, bins_per_side_ - 1); ++iy) {
      const size_t b = static_cast<size_t>(ix * bins_per_side_ + iy);
      for (int k = bin_start_[b]; k < bin_start_[b + 1]; ++k) {
        const Point& p = points_[static_cast<size_t>(k)];
        const double dx = p.x - x, dy = p.y - y;
        if (dx * dx + dy * dy > r2) continue;
        if (p.z < -config_.hole_depth) ++counts.below;
        else if (p.z < config_.min_obstacle_height) ++counts.ground;
        else if (p.z <= config_.max_obstacle_height) ++counts.above;
      }
    }
  }
  return counts;
}

Verdict DenseDetector::check(double x, double y, double radius) {
  const Counts c = count_points(x, y, radius);
  const double needed =
      std::max<double>(config_.min_obstacle_points, config_.min_obstacle_fraction * (c.ground + c.above + c.below));
  if (c.above >= needed || c.below >= needed) return Verdict::kObstacle;
  if (c.ground >= config_.min_ground_points) return Verdict::kFree;
  return Verdict::kUnknown;
}

}  // namespace ivoa::stereo
