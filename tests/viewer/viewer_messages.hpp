#pragma once
// Small hand-made messages for the viewer tests: a 4-cell grid whose cells
// sit at known pixels of a 320x200 image.
#include <cmath>
#include <limits>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/introspection_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::viewer::test {

inline constexpr int kWidth = 320, kHeight = 200;
inline const float kCellU[4] = {60, 130, 200, 270};
inline const float kCellV[4] = {150, 150, 150, 150};

inline image_t gray_image(int64_t utime, uint8_t level = 90) {
  return encode_image(cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(level, level, level)), image_t::PIXEL_FORMAT_BGR,
                      utime);
}

inline obstacle_grid_t grid(int64_t utime, std::vector<int8_t> states, const char* detector = "jppc") {
  obstacle_grid_t g{};
  g.utime = utime;
  g.detector = detector;
  g.num_x = 1;
  g.num_y = static_cast<int32_t>(states.size());
  g.num_cells = g.num_y;
  g.state = states;
  for (size_t i = 0; i < states.size(); ++i) {
    g.x.push_back(1.0f);
    g.y.push_back(static_cast<float>(i));
    g.u.push_back(kCellU[i]);
    g.v.push_back(kCellV[i]);
    g.in_image.push_back(1);
  }
  return g;
}

// The labels of a 1 x n grid, each with the two verdicts that give it.
inline introspection_labels_t labels(int64_t utime, std::vector<int8_t> label) {
  using L = introspection_labels_t;
  using G = obstacle_grid_t;
  introspection_labels_t l{};
  l.utime = utime;
  l.num_x = 1;
  l.num_cells = l.num_y = static_cast<int32_t>(label.size());
  l.label = label;
  for (size_t i = 0; i < label.size(); ++i) {
    const int8_t k = label[i];
    const bool none = k == L::LABEL_NONE;
    l.stereo_state.push_back(none ? G::STATE_UNKNOWN
                                  : (k == L::LABEL_TP || k == L::LABEL_FP ? G::STATE_OBSTACLE : G::STATE_FREE));
    l.depth_state.push_back(none ? G::STATE_UNKNOWN
                                 : (k == L::LABEL_TP || k == L::LABEL_FN ? G::STATE_OBSTACLE : G::STATE_FREE));
    l.x.push_back(1.0f);
    l.y.push_back(static_cast<float>(i));
    l.u.push_back(kCellU[i]);
    l.v.push_back(kCellV[i]);
  }
  return l;
}

// Heatmaps of 20 px patches at stride 20 over the image: P(FP) = 1 in the
// left half, 0 in the right; uncertainty rising left to right.
inline introspection_t introspection(int64_t utime, std::vector<int8_t> predicted = {}) {
  introspection_t h{};
  h.utime = utime;
  h.model_id = "test";
  h.mc_passes = 4;
  h.image_width = kWidth;
  h.image_height = kHeight;
  h.patch_size = 20;
  h.stride = 20;
  h.rows = kHeight / 20;
  h.cols = kWidth / 20;
  h.num_cells = h.rows * h.cols;
  for (int r = 0; r < h.rows; ++r)
    for (int c = 0; c < h.cols; ++c) {
      const bool left = c < h.cols / 2;
      h.prob_fp.push_back(left ? 1.0f : 0.0f);
      h.prob_fn.push_back(0.0f);
      h.prob_tp.push_back(0.0f);
      h.prob_tn.push_back(left ? 0.0f : 1.0f);
      h.uncertainty.push_back(0.01f * static_cast<float>(c));
      h.class_variance.push_back(0.0f);
    }
  for (size_t i = 0; i < predicted.size(); ++i) {
    h.query_x.push_back(1.0f);
    h.query_y.push_back(static_cast<float>(i));
    h.query_u.push_back(kCellU[i]);
    h.query_v.push_back(kCellV[i]);
    h.query_class.push_back(predicted[i]);
    h.query_probability.push_back(0.9f);
    h.query_uncertainty.push_back(0.001f);
    h.query_announced.push_back(i % 2 == 0);
    h.query_verdict.push_back(obstacle_grid_t::STATE_UNKNOWN);
    h.query_verdict_class.push_back(introspection_labels_t::LABEL_NONE);
    h.query_p_wrong.push_back(std::numeric_limits<float>::quiet_NaN());
    h.query_p_wrong_variance.push_back(std::numeric_limits<float>::quiet_NaN());
    h.query_verdict_announced.push_back(0);
  }
  h.num_queries = static_cast<int32_t>(predicted.size());
  return h;
}

}  // namespace ivoa::viewer::test
