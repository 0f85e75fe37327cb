#include "ivoa/stereo/jpp_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ivoa::stereo {
namespace {

DaisyParams daisy_params(const JppConfig& c) { return {c.daisy_R, c.daisy_Q, c.daisy_T, c.daisy_H}; }

float l1(const float* a, const float* b, int stride) {
  if (stride == 4)  // JPP's 3-float descriptor, padded: the common case, unrolled.
    return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) + std::abs(a[3] - b[3]);
  float sum = 0;
  for (int i = 0; i < stride; ++i) sum += std::abs(a[i] - b[i]);
  return sum;
}

uint64_t pair_key(cv::Point l, cv::Point r) {
  auto u16 = [](int v) { return static_cast<uint64_t>(static_cast<uint16_t>(v)); };
  return u16(l.x) | u16(l.y) << 16 | u16(r.x) << 32 | u16(r.y) << 48;
}

}  // namespace

JppMatcher::JppMatcher(const JppConfig& config)
    : config_(config), left_(daisy_params(config)), right_(daisy_params(config)) {
  validate(config_);
}

void JppMatcher::set_images(const cv::Mat& left_gray, const cv::Mat& right_gray) {
  if (left_gray.size() != right_gray.size())
    throw std::invalid_argument("JPP matcher: left and right rectified images differ in size");
  if (left_gray.cols > 65535 || left_gray.rows > 65535)
    throw std::invalid_argument("JPP matcher: images larger than 65535 pixels are not supported");
  left_.set_image(left_gray);
  right_.set_image(right_gray);
  cp_cache_.clear();
  cp_tests_ = cp_cache_hits_ = 0;
}

std::optional<double> JppMatcher::cost(cv::Point l, cv::Point r) {
  if (!inside(l) || !inside(r)) return std::nullopt;
  const int w = config_.SAD_window_size;
  const int stride = left_.stride();
  // Window pixels whose descriptors are complete (every sample point inside
  // the image) on both sides. DAISY reads zeros beyond the border, so JPP's
  // descriptors near the right edge (samples reach 5 px ahead) never matched.
  const DaisyDescriptors::Reach reach = left_.reach();
  const int x_min = reach.left, x_max = size().width - 1 - reach.right;
  const int y_min = reach.up, y_max = size().height - 1 - reach.down;
  const int dx_lo = std::max({-w, x_min - l.x, x_min - r.x}), dx_hi = std::min({w, x_max - l.x, x_max - r.x});
  const int dy_lo = std::max({-w, y_min - l.y, y_min - r.y}), dy_hi = std::min({w, y_max - l.y, y_max - r.y});
  const int compared = std::max(0, dx_hi - dx_lo + 1) * std::max(0, dy_hi - dy_lo + 1);
  const int window = (2 * w + 1) * (2 * w + 1);
  if (compared == 0 || compared < config_.min_window_fraction * window) return std::nullopt;
  float sum = 0;
  for (int dy = dy_lo; dy <= dy_hi; ++dy) {
    for (int dx = dx_lo; dx <= dx_hi; ++dx)
      sum += l1(left_.at(l.x + dx, l.y + dy), right_.at(r.x + dx, r.y + dy), stride);
  }
  return static_cast<double>(sum) / compared;
}

PointCheck JppMatcher::confident_positive(cv::Point l, cv::Point r, double* cost_out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (cost_out) *cost_out = nan;
  if (!inside(l) || !inside(r)) return PointCheck::kUnobserved;
  ++cp_tests_;
  const uint64_t key = pair_key(l, r);
  auto it = cp_cache_.find(key);
  if (it != cp_cache_.end()) {
    ++cp_cache_hits_;
  } else {
    CachedCheck check{PointCheck::kUnobserved, nan};
    if (config_.texture_gate <= 0 || texture(l) >= config_.texture_gate) {
      if (const auto c = cost(l, r)) {
        check.cost = *c;
        check.verdict = *c < config_.conf_pos_thresh ? PointCheck::kMatch : PointCheck::kNoMatch;
      }
    }
    it = cp_cache_.emplace(key, check).first;
  }
  if (cost_out) *cost_out = it->second.cost;
  return it->second.verdict;
}

bool JppMatcher::confident_negative(cv::Point l, cv::Point r) {
  const auto c = cost(l, r);
  return c && *c > config_.conf_neg_thresh;
}

double JppMatcher::texture(cv::Point l) const {
  const cv::Mat& layer = left_.base_layer(0);
  const int w = config_.SAD_window_size;
  const cv::Rect window = cv::Rect(l.x - w, l.y - w, 2 * w + 1, 2 * w + 1) & cv::Rect(0, 0, layer.cols, layer.rows);
  if (window.area() == 0) return 0.0;
  return cv::mean(layer(window))[0] * 255.0;
}

JppMatcher::Stats JppMatcher::stats() const {
  return {cp_tests_, cp_cache_hits_, left_.computed_count() + right_.computed_count()};
}

}  // namespace ivoa::stereo
