#pragma once
// JPP's matching cost and point predicates on a rectified gray pair
// (ivoa_jpp_spec.md §1.4-1.5): the mean L1 distance between DAISY
// descriptors over a (2w+1)^2 window around a left pixel and its right
// counterpart, thresholded into "confident positive" (a surface is there)
// and "confident negative" (confidently nothing there). Works in pixel
// space, so the stereo evaluation tool uses it directly on any rectified pair.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <unordered_map>

#include <opencv2/core.hpp>

#include "ivoa/stereo/config.hpp"
#include "ivoa/stereo/daisy.hpp"

namespace ivoa::stereo {

enum class PointCheck {
  kMatch,       // CP true: cost < conf_pos_thresh
  kNoMatch,     // CP false
  kUnobserved,  // no verdict: outside an image, window mostly outside, or gated as texture-less
};

class JppMatcher {
 public:
  explicit JppMatcher(const JppConfig& config);

  // Rectified 8-bit gray pair of one size. Resets descriptors and caches.
  // Windows may then be asked for inside the given regions only (empty: the
  // whole image); each image must be valid within
  // descriptor_margin(region) (see DaisyDescriptors).
  void set_images(const cv::Mat& left_gray, const cv::Mat& right_gray, cv::Rect left_region = {},
                  cv::Rect right_region = {});
  cv::Rect descriptor_margin(cv::Rect region, cv::Size size) const { return left_.region_with_margin(region, size); }
  // Whether the windows of this pair lie inside the regions given to
  // set_images (always true for the whole image).
  bool covers(cv::Point left, cv::Point right) const;
  cv::Size size() const { return left_.image_size(); }

  // Mean per-pixel L1 descriptor distance over the window pixels whose
  // descriptors are complete in both images; empty if the centres are
  // outside or fewer than min_window_fraction of the window is usable. (JPP
  // divides by the full window, biasing border windows towards "match", and
  // compares zero-padded descriptors near the right edge, biasing them
  // towards "no match".)
  std::optional<double> cost(cv::Point left, cv::Point right);

  // CP, cached per frame on the (left, right) pixel pair. JPP caches on the
  // left pixel only, so two hypotheses through one left pixel at different
  // disparities shared a verdict; that aliasing is fixed here. `cost`, if
  // given, receives the window cost (NaN when unobserved).
  PointCheck confident_positive(cv::Point left, cv::Point right, double* cost = nullptr);
  // CN: true iff the cost exceeds conf_neg_thresh; false when unobserved.
  bool confident_negative(cv::Point left, cv::Point right);

  // Mean positive horizontal gradient over the left window, 8-bit gray
  // levels per pixel (the texture gate's measure).
  double texture(cv::Point left) const;

  struct Stats {
    int64_t cp_tests = 0;
    int64_t cp_cache_hits = 0;
    int64_t descriptors = 0;  // computed, both images
  };
  Stats stats() const;

 private:
  bool inside(cv::Point p) const { return p.x >= 0 && p.y >= 0 && p.x < size().width && p.y < size().height; }
  // The part of the window around (left, right) where both descriptors are
  // complete, as offsets from the centres; empty (compared == 0) if none.
  struct Window {
    int dx_lo = 0, dx_hi = -1, dy_lo = 0, dy_hi = -1;
    int compared() const { return std::max(0, dx_hi - dx_lo + 1) * std::max(0, dy_hi - dy_lo + 1); }
  };
  Window window(cv::Point left, cv::Point right) const;

  JppConfig config_;
  DaisyDescriptors left_, right_;
  struct CachedCheck {
    PointCheck verdict;
    double cost;
  };
  std::unordered_map<uint64_t, CachedCheck> cp_cache_;
  int64_t cp_tests_ = 0, cp_cache_hits_ = 0;
};

}  // namespace ivoa::stereo
