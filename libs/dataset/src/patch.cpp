#include "ivoa/dataset/patch.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/query_grid.hpp"

namespace ivoa::dataset {

cv::Mat extract_patch(const cv::Mat& image, double u, double v, int patch_size) {
  return cut_patch(image, 1, u, v, patch_size, patch_size);
}

PatchTruth summarize_truth(const cv::Mat& phenomena, const cv::Mat& surface, double u, double v, int patch_size) {
  PatchTruth t;
  const cv::Rect centre = patch_rect(u, v, patch_size / 2) & cv::Rect(0, 0, phenomena.cols, phenomena.rows);
  if (centre.empty()) return t;
  std::array<int, 8> bit_counts{};
  std::array<int, 256> surface_counts{};
  for (int r = centre.y; r < centre.y + centre.height; ++r) {
    const uint8_t* p = phenomena.ptr<uint8_t>(r);
    const uint8_t* s = surface.empty() ? nullptr : surface.ptr<uint8_t>(r);
    for (int c = centre.x; c < centre.x + centre.width; ++c) {
      t.phenomena |= p[c];
      for (int b = 0; b < 8; ++b) bit_counts[static_cast<size_t>(b)] += (p[c] >> b) & 1;
      if (s) ++surface_counts[s[c]];
    }
  }
  int best = 0;
  for (int b = 0; b < 8; ++b)
    if (bit_counts[static_cast<size_t>(b)] > best) {
      best = bit_counts[static_cast<size_t>(b)];
      t.phenomenon = 1 << b;
    }
  if (!surface.empty()) {
    const auto most = std::max_element(surface_counts.begin(), surface_counts.end());
    t.surface = static_cast<int32_t>(most - surface_counts.begin());
  }
  return t;
}

}  // namespace ivoa::dataset
