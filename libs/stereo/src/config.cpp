#include "ivoa/stereo/config.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace ivoa::stereo {
namespace {

constexpr int kMaxDisparities = 1024;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("stereo detector config: " + what);
}

}  // namespace

void validate(const SgbmConfig& c) {
  require(c.rect_scale >= 0.05 && c.rect_scale <= 1, "sgbm_rect_scale must be in [0.05, 1]");
  require(c.num_disparities > 0 && c.num_disparities <= kMaxDisparities && c.num_disparities % 16 == 0,
          "sgbm_num_disparities must be a multiple of 16 in [16, 1024]");
  // not std::abs: -INT_MIN overflows (to INT_MIN, which passed)
  require(c.min_disparity >= -kMaxDisparities && c.min_disparity <= kMaxDisparities,
          "sgbm_min_disparity must be in [-1024, 1024]");
  require(c.block_size >= 1 && c.block_size <= 51 && c.block_size % 2 == 1, "sgbm_block_size must be odd, 1 to 51");
  require(c.p1 >= 0 && c.p2 >= 0 && c.p2 <= 1000000, "sgbm_p1 and sgbm_p2 must be in [0, 1000000]");
  require(c.p2 == 0 || c.p2 > c.p1, "sgbm_p2 must exceed sgbm_p1");
  require(c.mode == "3way" || c.mode == "sgbm" || c.mode == "hh", "sgbm_mode must be 3way, sgbm or hh");
}

void validate(const JppConfig& c) {
  require(c.rect_scale >= 0.05 && c.rect_scale <= 1, "rect_scale must be in [0.05, 1]");
  // JPP's descriptor is a few rings of a few histograms, a few pixels wide:
  // far larger ones hang the detector on every frame.
  require(c.daisy_R > 0 && c.daisy_R <= 100 && c.daisy_Q >= 1 && c.daisy_Q <= 16 && c.daisy_T >= 1 && c.daisy_T <= 32 &&
              c.daisy_H >= 1 && c.daisy_H <= 32,
          "daisy_R must be in (0, 100], daisy_Q in [1, 16], daisy_T and daisy_H in [1, 32]");
  require(c.SAD_window_size >= 0 && c.SAD_window_size <= 50, "SAD_window_size must be in [0, 50]");
  require(c.conf_pos_thresh > 0 && std::isfinite(c.conf_pos_thresh), "conf_pos_thresh must be positive");
  // JPP's config is in mm: 50 there is 0.05 here. Finer than 5 mm, a
  // footprint holds so many samples that their count overflows.
  require(c.grid_size >= 0.005 && c.grid_size <= 1.0, "grid_size must be in [0.005, 1] metres (JPP's .cfg uses mm)");
  require(c.footprint == "disc" || c.footprint == "half_box", "jpp_footprint must be 'disc' or 'half_box'");
  require(c.min_window_fraction > 0 && c.min_window_fraction <= 1, "jpp_min_window_fraction must be in (0, 1]");
  require(c.texture_gate >= 0, "jpp_texture_gate must be >= 0");
}

void validate(const DenseConfig& c) {
  validate(c.sgbm);
  require(c.min_obstacle_height > 0 && c.max_obstacle_height > c.min_obstacle_height,
          "need 0 < dense_min_obstacle_height < dense_max_obstacle_height");
  require(c.hole_depth > 0, "dense_hole_depth must be positive");
  require(c.min_obstacle_points >= 1 && c.min_ground_points >= 1, "dense point counts must be >= 1");
  require(c.min_obstacle_fraction >= 0 && c.min_obstacle_fraction <= 1,
          "dense_min_obstacle_fraction must be in [0, 1]");
  require(c.max_range > 0 && c.max_range <= 100, "dense_max_range must be in (0, 100] m");
}

}  // namespace ivoa::stereo
