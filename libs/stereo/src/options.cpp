#include "ivoa/stereo/options.hpp"

#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "ivoa/stereo/config.hpp"

namespace ivoa::stereo {

namespace {
const char* kJppGroup = "JPP-C (jppc)";
const char* kSgbmGroup = "Dense (SGBM)";
}  // namespace

void add_jpp_matcher_options(CLI::App& app, JppConfig& c) {
  auto add = [&](const char* flag, auto& value, const char* help) {
    app.add_option(flag, value, help)->capture_default_str()->group(kJppGroup);
  };
  add("--daisy_R", c.daisy_R, "DAISY outer ring radius, pixels");
  add("--daisy_Q", c.daisy_Q, "DAISY rings");
  add("--daisy_T", c.daisy_T, "DAISY angles per ring");
  add("--daisy_H", c.daisy_H, "DAISY orientation bins");
  add("--SAD_window_size", c.SAD_window_size, "matching window half-width, pixels (5: 11x11)");
  add("--conf_pos_thresh", c.conf_pos_thresh, "CP: window cost below this is a match");
  add("--conf_neg_thresh", c.conf_neg_thresh, "CN: window cost above this is confidently empty (full JPP only)");
  add("--jpp_min_window_fraction", c.min_window_fraction,
      "window share that must lie inside both images for a verdict (JPP: none, divides by 121)");
  add("--jpp_texture_gate", c.texture_gate,
      "no verdict where the left window's mean positive x-gradient is below this, gray levels/px; 0 = off (JPP)");
}

void add_jpp_options(CLI::App& app, JppConfig& c) {
  app.add_option("--rect_scale", c.rect_scale, "rectified image size / raw size (0.5: 960x600 -> 480x300)")
      ->capture_default_str()
      ->group(kJppGroup);
  app.add_option("--grid_size", c.grid_size,
                 "step between ground samples of one footprint check, m (JPP grid_size, mm there; not --grid-spacing)")
      ->capture_default_str()
      ->group(kJppGroup);
  app.add_option("--jpp_footprint", c.footprint,
                 "ground samples of a footprint check: half_box (JPP's is_bot_clear: ahead of the point) or "
                 "disc (within r)")
      ->capture_default_str()
      ->check(CLI::IsMember({"disc", "half_box"}))
      ->group(kJppGroup);
  add_jpp_matcher_options(app, c);
}

void add_sgbm_matcher_options(CLI::App& app, SgbmConfig& c) {
  auto add = [&](const char* flag, auto& value, const char* help) {
    return app.add_option(flag, value, help)->capture_default_str()->group(kSgbmGroup);
  };
  add("--sgbm_mode", c.mode, "3way (fastest), sgbm, hh")->check(CLI::IsMember({"3way", "sgbm", "hh"}));
  add("--sgbm_min_disparity", c.min_disparity, "pixels");
  // OpenCV's StereoSGBM refuses others (an exception per frame, not a usage error).
  add("--sgbm_num_disparities", c.num_disparities, "disparity search range, pixels, multiple of 16")
      ->check(CLI::Validator(
          [](const std::string& v) {
            const int n = std::atoi(v.c_str());
            return n > 0 && n % 16 == 0 ? std::string() : "must be a positive multiple of 16, not " + v;
          },
          "", "multiple of 16"));
  add("--sgbm_block_size", c.block_size, "matching block side, pixels, odd")
      ->check(CLI::Validator(
          [](const std::string& v) {
            const int n = std::atoi(v.c_str());
            return n > 0 && n % 2 == 1 ? std::string() : "must be a positive odd number, not " + v;
          },
          "", "odd"));
  add("--sgbm_p1", c.p1, "small-change penalty (0: 8*block^2)");
  add("--sgbm_p2", c.p2, "large-change penalty (0: 32*block^2)");
  add("--sgbm_uniqueness_ratio", c.uniqueness_ratio, "percent margin of the best cost");
  add("--sgbm_speckle_window_size", c.speckle_window_size, "speckle filter region size, pixels (0: off)");
  add("--sgbm_speckle_range", c.speckle_range, "speckle filter disparity range");
  add("--sgbm_disp12_max_diff", c.disp12_max_diff, "left-right consistency, pixels (<0: off)");
  add("--sgbm_pre_filter_cap", c.pre_filter_cap, "prefilter clipping");
}

void add_dense_options(CLI::App& app, DenseConfig& c) {
  app.add_option("--sgbm_rect_scale", c.sgbm.rect_scale, "rectified image size / raw size")
      ->capture_default_str()
      ->group(kSgbmGroup);
  add_sgbm_matcher_options(app, c.sgbm);
  auto add = [&](const char* flag, auto& value, const char* help) {
    app.add_option(flag, value, help)->capture_default_str()->group(kSgbmGroup);
  };
  add("--dense_min_obstacle_height", c.min_obstacle_height,
      "points higher than this above the ground are obstacles, m");
  add("--dense_max_obstacle_height", c.max_obstacle_height, "points higher than this are above the robot, ignored, m");
  add("--dense_hole_depth", c.hole_depth,
      "points lower than this below the ground are obstacles (holes, reflections), m");
  add("--dense_min_obstacle_points", c.min_obstacle_points, "obstacle (or below-ground) points within r for OBSTACLE");
  add("--dense_min_obstacle_fraction", c.min_obstacle_fraction, "and at least this share of the valid points within r");
  add("--dense_min_ground_points", c.min_ground_points, "ground points within r for FREE");
  add("--dense_max_range", c.max_range, "points farther ahead or aside than this are ignored, m");
}

void add_detector_options(CLI::App& app, DetectorConfig& c) {
  add_jpp_options(app, c.jpp);
  add_dense_options(app, c.dense);
}

}  // namespace ivoa::stereo
