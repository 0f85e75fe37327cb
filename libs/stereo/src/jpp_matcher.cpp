#include "ivoa/stereo/jpp_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace ivoa::stereo {
namespace {

DaisyParams daisy_params(const JppConfig& c) { return {c.daisy_R, c.daisy_Q, c.daisy_T, c.daisy_H}; }

// Sum of |a - b| over n bytes. With SSE2, 16 bytes per instruction
// (psadbw); the last block reads up to 15 bytes past n, which the
// descriptor cache is padded for, and masks them out.
int sum_abs_diff(const uint8_t* a, const uint8_t* b, int n) {
#ifdef __SSE2__
  static const uint8_t kMaskBytes[32] = {0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
                                         0xff, 0xff, 0xff, 0xff, 0xff, 0,    0,    0,    0,    0,    0,
                                         0,    0,    0,    0,    0,    0,    0,    0,    0,    0};
  __m128i sum = _mm_setzero_si128();
  int i = 0;
  for (; i + 16 <= n; i += 16)
    sum = _mm_add_epi64(sum, _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i)),
                                          _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i))));
  if (i < n) {
    const __m128i mask = _mm_loadu_si128(reinterpret_cast<const __m128i*>(kMaskBytes + 16 - (n - i)));
    const __m128i va = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i)), mask);
    const __m128i vb = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i)), mask);
    sum = _mm_add_epi64(sum, _mm_sad_epu8(va, vb));
  }
  return _mm_cvtsi128_si32(sum) + _mm_cvtsi128_si32(_mm_unpackhi_epi64(sum, sum));
#else
  int sum = 0;
  for (int i = 0; i < n; ++i) sum += std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i]));
  return sum;
#endif
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

void JppMatcher::set_images(const cv::Mat& left_gray, const cv::Mat& right_gray, cv::Rect left_region,
                            cv::Rect right_region) {
  if (left_gray.size() != right_gray.size())
    throw std::invalid_argument("JPP matcher: left and right rectified images differ in size");
  if (left_gray.cols > 65535 || left_gray.rows > 65535)
    throw std::invalid_argument("JPP matcher: images larger than 65535 pixels are not supported");
  left_.set_image(left_gray, left_region);
  right_.set_image(right_gray, right_region);
  cp_cache_.clear();
  cp_tests_ = cp_cache_hits_ = 0;
}

JppMatcher::Window JppMatcher::window(cv::Point l, cv::Point r) const {
  // Window pixels whose descriptors are complete (every sample point inside
  // the image) on both sides. DAISY reads zeros beyond the border, so JPP's
  // descriptors near the right edge (samples reach 5 px ahead) never matched.
  const int w = config_.SAD_window_size;
  const DaisyDescriptors::Reach reach = left_.reach();
  const int x_min = reach.left, x_max = size().width - 1 - reach.right;
  const int y_min = reach.up, y_max = size().height - 1 - reach.down;
  return {std::max({-w, x_min - l.x, x_min - r.x}), std::min({w, x_max - l.x, x_max - r.x}),
          std::max({-w, y_min - l.y, y_min - r.y}), std::min({w, y_max - l.y, y_max - r.y})};
}

bool JppMatcher::covers(cv::Point l, cv::Point r) const {
  if (!inside(l) || !inside(r)) return true;
  const Window win = window(l, r);
  if (win.compared() == 0) return true;
  auto in = [&](const cv::Rect& region, cv::Point c) {
    return region.contains(c + cv::Point(win.dx_lo, win.dy_lo)) && region.contains(c + cv::Point(win.dx_hi, win.dy_hi));
  };
  return in(left_.region(), l) && in(right_.region(), r);
}

std::optional<double> JppMatcher::cost(cv::Point l, cv::Point r) {
  if (!inside(l) || !inside(r)) return std::nullopt;
  const Window win = window(l, r);
  const int w = config_.SAD_window_size;
  const int compared = win.compared();
  if (compared == 0 || compared < config_.min_window_fraction * (2 * w + 1) * (2 * w + 1)) return std::nullopt;
  if (!covers(l, r)) throw std::logic_error("JPP matcher: window outside the region its images were prepared for");
  const int stride = left_.stride();
  const int n = (win.dx_hi - win.dx_lo + 1) * stride;
  int sum = 0;
  for (int dy = win.dy_lo; dy <= win.dy_hi; ++dy) {
    const int xl = l.x + win.dx_lo, xr = r.x + win.dx_lo;
    const uint8_t* a = left_.row(l.y + dy, xl, l.x + win.dx_hi) + static_cast<ptrdiff_t>(xl) * stride;
    const uint8_t* b = right_.row(r.y + dy, xr, r.x + win.dx_hi) + static_cast<ptrdiff_t>(xr) * stride;
    sum += sum_abs_diff(a, b, n);
  }
  return sum / (DaisyDescriptors::kScale * compared);
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
  const cv::Rect window = cv::Rect(l.x - w, l.y - w, 2 * w + 1, 2 * w + 1) & left_.region();
  if (window.area() == 0) return 0.0;
  return cv::mean(layer(window))[0] * 255.0;
}

JppMatcher::Stats JppMatcher::stats() const {
  return {cp_tests_, cp_cache_hits_, left_.computed_count() + right_.computed_count()};
}

}  // namespace ivoa::stereo
