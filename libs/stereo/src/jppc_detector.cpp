#include "ivoa/stereo/jppc_detector.hpp"

#include <cmath>

namespace ivoa::stereo {
namespace {

cv::Point nearest_pixel(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))};
}

// Samples in [0, extent] at `step`, counted with integers.
int samples_up_to(double extent, double step) { return static_cast<int>(std::floor(extent / step + 1e-6)) + 1; }

}  // namespace

JppcDetector::JppcDetector(const RigCalibration& rig, const JppConfig& config)
    : rig_(rig), config_(config), rect_(rig, config.rect_scale), matcher_(config) {}

void JppcDetector::set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) {
  has_frame_ = false;
  to_gray_checked(left_raw, right_raw, rig_, left_gray_, right_gray_);
  rect_.rectify(left_gray_, right_gray_, left_rect_, right_rect_);
  matcher_.set_images(left_rect_, right_rect_);
  has_frame_ = true;
}

PointCheck JppcDetector::confident_positive(const Eigen::Vector3d& p_robot) {
  Eigen::Vector2d left, right;
  if (!has_frame_ || !rect_.project(p_robot, left, right)) return PointCheck::kUnobserved;
  return matcher_.confident_positive(nearest_pixel(left), nearest_pixel(right));
}

Verdict JppcDetector::check(double x, double y, double radius) {
  // JPP's is_bot_clear with col_check = false: the half box ahead of (x, y).
  const double step = config_.grid_size;
  const int n_forward = samples_up_to(radius, step);
  const int n_lateral = samples_up_to(2.0 * radius, step);
  bool unobserved = false;
  for (int i = 0; i < n_forward; ++i) {
    for (int j = 0; j < n_lateral; ++j) {
      const Eigen::Vector3d q(x + i * step, y - radius + j * step, 0.0);
      switch (confident_positive(q)) {
        case PointCheck::kNoMatch: return Verdict::kObstacle;
        case PointCheck::kUnobserved: unobserved = true; break;
        case PointCheck::kMatch: break;
      }
    }
  }
  return unobserved ? Verdict::kUnknown : Verdict::kFree;
}

}  // namespace ivoa::stereo
