#include "ivoa/core/query_grid.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace ivoa {

int grid_count(double lo, double hi, double step) {
  if (!(step > 0) || !(hi >= lo)) return 0;
  return static_cast<int>(std::floor((hi - lo) / step + 1e-6)) + 1;
}

cv::Rect patch_rect(double u, double v, int patch_size) {
  const int left = static_cast<int>(std::lround(u)) - patch_size / 2;
  const int top = static_cast<int>(std::lround(v)) - patch_size / 2;
  return {left, top, patch_size, patch_size};
}

QueryGrid::QueryGrid(const QueryGridConfig& config, const CameraModel& left_camera) : config_(config) {
  num_x_ = grid_count(config.x_min, config.x_max, config.spacing);
  num_y_ = grid_count(config.y_min, config.y_max, config.spacing);
  if (num_x_ == 0 || num_y_ == 0 || config.patch_size <= 0 || !(config.safety_radius > 0))
    throw std::invalid_argument(
        "query grid: need x_min <= x_max, y_min <= y_max, spacing > 0, "
        "safety_radius > 0 and patch_size > 0");
  const cv::Rect image(0, 0, left_camera.intrinsics().width, left_camera.intrinsics().height);
  cells_.resize(static_cast<size_t>(num_x_) * static_cast<size_t>(num_y_));
  for (int ix = 0; ix < num_x_; ++ix) {
    for (int iy = 0; iy < num_y_; ++iy) {
      QueryCell& cell = cells_[static_cast<size_t>(index(ix, iy))];
      cell.x = config.x_min + ix * config.spacing;
      cell.y = config.y_min + iy * config.spacing;
      cell.u = cell.v = std::numeric_limits<double>::quiet_NaN();
      const auto pixel = left_camera.project({cell.x, cell.y, 0.0});
      if (!pixel) continue;
      cell.projects = true;
      cell.u = pixel->x();
      cell.v = pixel->y();
      const cv::Rect patch = patch_rect(cell.u, cell.v, config.patch_size);
      cell.in_image = (patch & image) == patch;
    }
  }
}

int QueryGrid::count_in_image() const {
  int n = 0;
  for (const auto& c : cells_) n += c.in_image ? 1 : 0;
  return n;
}

}  // namespace ivoa
