#pragma once
// Rectification of a region of the rectified image only (JPP-C rectifies
// just where the grid's windows fall). Uses core's rectification maps,
// recovered by rectifying images of the raw pixel coordinates, as
// fixed-point bilinear taps. Internal to libs/stereo.
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/rectification.hpp"

namespace ivoa::stereo {

class RegionRemap {
 public:
  // The left and right remaps of `rect`, for raw images of the rig's sizes.
  static std::pair<RegionRemap, RegionRemap> for_pair(const StereoRectification& rect, const RigCalibration& rig);

  // 8-bit gray or BGR raw image -> 8-bit gray rectified pixels inside
  // `region` of `out` (rectified size; other pixels untouched). BGR is
  // converted to gray on the raw rows the region reads, then remapped.
  void apply(const cv::Mat& raw, cv::Rect region, cv::Mat& out);

 private:
  RegionRemap(const cv::Mat& map_x, const cv::Mat& map_y, cv::Size raw_size);

  static constexpr int kFracBits = 5;  // 1/32 pixel, as OpenCV's remap
  cv::Size raw_size_, rect_size_;
  std::vector<int32_t> offset_;  // raw index of the top-left tap; -1: outside the raw image (black)
  std::vector<uint8_t> frac_x_, frac_y_;
  std::vector<int> first_row_, last_row_;  // raw rows each rectified row reads
  cv::Mat gray_;                           // raw gray rows (BGR input)
};

}  // namespace ivoa::stereo
