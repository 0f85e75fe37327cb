#include "region_remap.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace ivoa::stereo {
namespace {

cv::Mat pixel_coordinates(const CameraIntrinsics& camera, int axis) {
  cv::Mat out(camera.height, camera.width, CV_32F);
  for (int v = 0; v < out.rows; ++v) {
    float* row = out.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u) row[u] = static_cast<float>(axis == 0 ? u : v);
  }
  return out;
}

}  // namespace

std::pair<RegionRemap, RegionRemap> RegionRemap::for_pair(const StereoRectification& rect, const RigCalibration& rig) {
  // Rectifying an image of its own x (or y) coordinates yields the map:
  // bilinear interpolation of a linear function is exact. Core keeps its
  // maps private; this recovers them without redoing the rectification.
  cv::Mat lx, rx, ly, ry;
  rect.rectify(pixel_coordinates(rig.left, 0), pixel_coordinates(rig.right, 0), lx, rx);
  rect.rectify(pixel_coordinates(rig.left, 1), pixel_coordinates(rig.right, 1), ly, ry);
  return {RegionRemap(lx, ly, {rig.left.width, rig.left.height}),
          RegionRemap(rx, ry, {rig.right.width, rig.right.height})};
}

RegionRemap::RegionRemap(const cv::Mat& map_x, const cv::Mat& map_y, cv::Size raw_size)
    : raw_size_(raw_size), rect_size_(map_x.size()) {
  const size_t n = static_cast<size_t>(rect_size_.area());
  offset_.assign(n, -1);
  frac_x_.assign(n, 0);
  frac_y_.assign(n, 0);
  first_row_.assign(static_cast<size_t>(rect_size_.height), raw_size.height);
  last_row_.assign(static_cast<size_t>(rect_size_.height), -1);
  const float scale = 1 << kFracBits;
  for (int v = 0; v < rect_size_.height; ++v) {
    for (int u = 0; u < rect_size_.width; ++u) {
      const size_t i = static_cast<size_t>(v) * static_cast<size_t>(rect_size_.width) + static_cast<size_t>(u);
      const int fx = static_cast<int>(std::lround(map_x.at<float>(v, u) * scale));
      const int fy = static_cast<int>(std::lround(map_y.at<float>(v, u) * scale));
      const int x0 = fx >> kFracBits, y0 = fy >> kFracBits;
      // Both taps of each axis inside the raw image (core's remap blends in
      // black outside; alpha-0 rectification keeps that to the very edge).
      if (x0 < 0 || y0 < 0 || x0 + 1 >= raw_size.width || y0 + 1 >= raw_size.height) continue;
      offset_[i] = y0 * raw_size.width + x0;
      frac_x_[i] = static_cast<uint8_t>(fx & ((1 << kFracBits) - 1));
      frac_y_[i] = static_cast<uint8_t>(fy & ((1 << kFracBits) - 1));
      first_row_[static_cast<size_t>(v)] = std::min(first_row_[static_cast<size_t>(v)], y0);
      last_row_[static_cast<size_t>(v)] = std::max(last_row_[static_cast<size_t>(v)], y0 + 1);
    }
  }
}

void RegionRemap::apply(const cv::Mat& raw, cv::Rect region, cv::Mat& out) {
  CV_Assert(raw.size() == raw_size_ && raw.depth() == CV_8U && out.size() == rect_size_ && out.type() == CV_8UC1);
  region &= cv::Rect(cv::Point(0, 0), rect_size_);
  if (region.area() == 0) return;
  const uint8_t* src = raw.data;
  if (raw.channels() == 3) {
    int first = raw_size_.height, last = -1;
    for (int v = region.y; v < region.y + region.height; ++v) {
      first = std::min(first, first_row_[static_cast<size_t>(v)]);
      last = std::max(last, last_row_[static_cast<size_t>(v)]);
    }
    if (gray_.size() != raw_size_) gray_.create(raw_size_, CV_8UC1);
    if (last >= first) {
      cv::Mat rows = gray_.rowRange(first, last + 1);
      cv::cvtColor(raw.rowRange(first, last + 1), rows, cv::COLOR_BGR2GRAY);
    }
    src = gray_.data;
  } else {
    CV_Assert(raw.isContinuous());
  }
  const int step = raw_size_.width, one = 1 << kFracBits;
  constexpr int kRound = 1 << (2 * kFracBits - 1);
  for (int v = region.y; v < region.y + region.height; ++v) {
    uint8_t* dst = out.ptr<uint8_t>(v);
    const size_t row = static_cast<size_t>(v) * static_cast<size_t>(rect_size_.width);
    for (int u = region.x; u < region.x + region.width; ++u) {
      const size_t i = row + static_cast<size_t>(u);
      const int32_t at = offset_[i];
      if (at < 0) {
        dst[u] = 0;
        continue;
      }
      const uint8_t* p = src + at;
      const int fx = frac_x_[i], fy = frac_y_[i];
      const int top = p[0] * (one - fx) + p[1] * fx, bottom = p[step] * (one - fx) + p[step + 1] * fx;
      dst[u] = static_cast<uint8_t>((top * (one - fy) + bottom * fy + kRound) >> (2 * kFracBits));
    }
  }
}

}  // namespace ivoa::stereo
