#include "ivoa/core/footprint_patch.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace ivoa {
namespace {

// Mean pixel distance from cell i to its projecting lateral neighbours (same
// grid row, y +- spacing); 0 if none.
double lateral_step_px(int num_y, size_t i, const std::vector<float>& u, const std::vector<float>& v) {
  const int iy = static_cast<int>(i % static_cast<size_t>(num_y));
  double sum = 0;
  int n = 0;
  for (const int step : {-1, 1}) {
    if (iy + step < 0 || iy + step >= num_y) continue;
    const size_t j = static_cast<size_t>(static_cast<long>(i) + step);
    if (std::isnan(u[j])) continue;
    sum += std::hypot(u[j] - u[i], v[j] - v[i]);
    ++n;
  }
  return n ? sum / n : 0.0;
}

// Largest even side whose patch_rect around (u, v) stays inside the image.
int largest_inside(double u, double v, cv::Size image) {
  const long column = std::lround(u), row = std::lround(v);
  const long half = std::min({column, image.width - column, row, image.height - row});
  return static_cast<int>(std::max(0L, 2 * half));
}

}  // namespace

std::vector<int> footprint_patch_sides(const QueryGridConfig& grid, int num_x, int num_y, const std::vector<float>& u,
                                       const std::vector<float>& v, cv::Size image, double scale) {
  const size_t n = static_cast<size_t>(num_x) * static_cast<size_t>(num_y);
  if (num_x <= 0 || num_y <= 0 || u.size() != n || v.size() != n)
    throw std::invalid_argument("footprint_patch_sides: " + std::to_string(u.size()) + " cells for a " +
                                std::to_string(num_x) + "x" + std::to_string(num_y) + " grid");
  std::vector<int> sides(n, grid.patch_size);
  if (!(scale > 0)) return sides;
  for (size_t i = 0; i < n; ++i) {
    if (std::isnan(u[i])) continue;
    const double disc_px = lateral_step_px(num_y, i, u, v) * 2 * grid.safety_radius / grid.spacing;
    const int wanted = 2 * static_cast<int>(std::lround(scale * disc_px / 2));
    const int side = std::min(wanted, largest_inside(u[i], v[i], image));
    sides[i] = std::max(side, grid.patch_size);
  }
  return sides;
}

cv::Mat cut_patch(const cv::Mat& stacked, int views, double u, double v, int side, int out_size) {
  if (views < 1 || stacked.rows % views != 0)
    throw std::invalid_argument("cut_patch: " + std::to_string(stacked.rows) + " rows do not hold " +
                                std::to_string(views) + " views");
  const int height = stacked.rows / views;
  const cv::Rect rect = patch_rect(u, v, side);
  if ((rect & cv::Rect(0, 0, stacked.cols, height)) != rect) return {};
  std::vector<cv::Mat> parts;
  for (int k = 0; k < views; ++k) {
    const cv::Mat square = stacked(rect + cv::Point(0, k * height));
    cv::Mat part;
    if (side == out_size) part = square.clone();
    else
      cv::resize(square, part, cv::Size(out_size, out_size), 0, 0, side > out_size ? cv::INTER_AREA : cv::INTER_LINEAR);
    parts.push_back(std::move(part));
  }
  if (views == 1) return parts[0];
  cv::Mat out;
  cv::vconcat(parts, out);
  return out;
}

std::vector<cv::Mat> cut_patches(const cv::Mat& stacked, int views, const std::vector<PatchSquare>& squares,
                                 int out_size, bool parallel) {
  std::vector<cv::Mat> patches(squares.size());
  const auto cut = [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const PatchSquare& q = squares[static_cast<size_t>(i)];
      patches[static_cast<size_t>(i)] = cut_patch(stacked, views, q.u, q.v, q.side, out_size);
    }
  };
  const cv::Range all(0, static_cast<int>(squares.size()));
  if (parallel) cv::parallel_for_(all, cut, static_cast<double>(squares.size()));
  else cut(all);
  return patches;
}

}  // namespace ivoa
