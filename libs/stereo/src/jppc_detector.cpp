#include "ivoa/stereo/jppc_detector.hpp"

#include <cmath>
#include <limits>

#include "region_remap.hpp"

namespace ivoa::stereo {
namespace {

cv::Point nearest_pixel(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::floor(p.x() + 0.5)), static_cast<int>(std::floor(p.y() + 0.5))};
}

// Samples in [0, extent] at `step`, counted with integers.
int samples_up_to(double extent, double step) { return static_cast<int>(std::floor(extent / step + 1e-6)) + 1; }

cv::Rect bounding(const cv::Rect& a, const cv::Rect& b) { return a.area() == 0 ? b : a | b; }

}  // namespace

JppcDetector::JppcDetector(const RigCalibration& rig, const JppConfig& config)
    : rig_(rig), config_(config), rect_(rig, config.rect_scale), matcher_(config) {
  auto [left, right] = RegionRemap::for_pair(rect_, rig);
  remap_left_ = std::make_unique<RegionRemap>(std::move(left));
  remap_right_ = std::make_unique<RegionRemap>(std::move(right));
  left_rect_ = cv::Mat::zeros(rect_.size(), CV_8UC1);
  right_rect_ = cv::Mat::zeros(rect_.size(), CV_8UC1);
}

JppcDetector::~JppcDetector() = default;

void JppcDetector::set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) {
  has_frame_ = prepared_ = whole_image_ = false;
  check_frame(left_raw, right_raw, rig_);
  left_raw_ = left_raw.isContinuous() ? left_raw : left_raw.clone();  // shared, rectified in evaluate()
  right_raw_ = right_raw.isContinuous() ? right_raw : right_raw.clone();
  has_frame_ = true;
}

void JppcDetector::prepare(cv::Rect left_region, cv::Rect right_region) {
  const cv::Rect image(cv::Point(0, 0), rect_.size());
  const cv::Rect left_area = left_region.area() > 0 ? matcher_.descriptor_margin(left_region, rect_.size()) : image;
  const cv::Rect right_area = right_region.area() > 0 ? matcher_.descriptor_margin(right_region, rect_.size()) : image;
  remap_left_->apply(left_raw_, left_area, left_rect_);
  remap_right_->apply(right_raw_, right_area, right_rect_);
  matcher_.set_images(left_rect_, right_rect_, left_region, right_region);
  prepared_ = true;
  whole_image_ = left_region.area() == 0 && right_region.area() == 0;
}

JppcDetector::Projection JppcDetector::project(const Eigen::Vector3d& p_robot) const {
  Eigen::Vector2d left, right;
  if (!rect_.project(p_robot, left, right)) return {false, {}, {}};
  return {true, nearest_pixel(left), nearest_pixel(right)};
}

template <class Visit>
void JppcDetector::for_each_sample(double x, double y, double radius, Visit visit) const {
  const double step = config_.grid_size;
  if (config_.footprint == "half_box") {
    // JPP's is_bot_clear with col_check = false: the half box ahead of (x, y).
    const int n_forward = samples_up_to(radius, step), n_lateral = samples_up_to(2.0 * radius, step);
    for (int i = 0; i < n_forward; ++i)
      for (int j = 0; j < n_lateral; ++j)
        if (!visit(Eigen::Vector3d(x + i * step, y - radius + j * step, 0.0))) return;
    return;
  }
  // The lattice points within r of (x, y) (integer steps, a small tolerance
  // so points exactly at r are in).
  const int n = samples_up_to(radius, step) - 1;
  const double limit = radius * radius * (1.0 + 1e-9);
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      if ((i * i + j * j) * step * step <= limit)
        if (!visit(Eigen::Vector3d(x + i * step, y + j * step, 0.0))) return;
}

PointCheck JppcDetector::confident_positive(const Eigen::Vector3d& p_robot, double* cost) {
  if (cost) *cost = std::numeric_limits<double>::quiet_NaN();
  const Projection p = project(p_robot);
  if (!has_frame_ || !p.valid) return PointCheck::kUnobserved;
  if (!prepared_ || !matcher_.covers(p.left, p.right)) prepare({}, {});
  return matcher_.confident_positive(p.left, p.right, cost);
}

Verdict JppcDetector::check(double x, double y, double radius) {
  bool obstacle = false, unobserved = false;
  for_each_sample(x, y, radius, [&](const Eigen::Vector3d& q) {
    switch (confident_positive(q)) {
      case PointCheck::kNoMatch: obstacle = true; return false;  // one failing sample decides
      case PointCheck::kUnobserved: unobserved = true; break;
      case PointCheck::kMatch: break;
    }
    return true;
  });
  if (obstacle) return Verdict::kObstacle;
  return unobserved ? Verdict::kUnknown : Verdict::kFree;
}

Evidence JppcDetector::evidence(double x, double y, double radius) {
  Evidence e;
  bool obstacle = false, unobserved = false;
  for_each_sample(x, y, radius, [&](const Eigen::Vector3d& q) {
    double cost = 0;
    const PointCheck c = confident_positive(q, &cost);
    obstacle |= c == PointCheck::kNoMatch;
    unobserved |= c == PointCheck::kUnobserved;
    e.values.push_back(static_cast<float>(cost));
    return true;  // every sample, unlike check()
  });
  e.verdict = obstacle ? Verdict::kObstacle : unobserved ? Verdict::kUnknown : Verdict::kFree;
  return e;
}

void JppcDetector::evaluate(const QueryGrid& grid, obstacle_grid_t& out) {
  if (has_frame_ && !whole_image_) {
    // Prepare only where the grid's windows fall.
    const cv::Rect image(cv::Point(0, 0), rect_.size());
    const int w = config_.SAD_window_size;
    cv::Rect left_region, right_region;
    for (const QueryCell& cell : grid.cells()) {
      if (!cell.projects) continue;
      for_each_sample(cell.x, cell.y, grid.config().safety_radius, [&](const Eigen::Vector3d& q) {
        const Projection p = project(q);
        if (p.valid && image.contains(p.left) && image.contains(p.right)) {
          left_region = bounding(left_region, cv::Rect(p.left.x - w, p.left.y - w, 2 * w + 1, 2 * w + 1) & image);
          right_region = bounding(right_region, cv::Rect(p.right.x - w, p.right.y - w, 2 * w + 1, 2 * w + 1) & image);
        }
        return true;
      });
    }
    if (left_region.area() > 0) prepare(left_region, right_region);
  }
  ObstacleDetector::evaluate(grid, out);
}

}  // namespace ivoa::stereo
