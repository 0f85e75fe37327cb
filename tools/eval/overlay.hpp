#pragma once
// Per-frame figures like the IVOA paper's: the left image with the ground
// query grid (outer ring = the label from the monitor, inner dot = the
// introspection prediction), the failure heatmap P(FP) + P(FN), and the
// uncertainty heatmap, side by side.
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/introspection/model.hpp"

namespace ivoa::tools {

struct LabelledCell {
  double u = 0, v = 0;
  int label = -1;      // 0 TP, 1 TN, 2 FP, 3 FN; -1 none
  int predicted = -1;  // idem; -1 not predicted
  bool announced = true;
  int patch_side = 0;  // the square the model sees around (u, v), pixels
};

// Colours of the four classes (BGR), as in the reference code's figures:
// TP green, TN blue, FP orange, FN red.
cv::Scalar class_colour(int label);

cv::Mat draw_grid(const cv::Mat& left_bgr, const std::vector<LabelledCell>& cells);
// A heatmap (rows x cols, CV_32F) upsampled to the image and blended over it.
cv::Mat draw_heatmap(const cv::Mat& left_bgr, const introspection::Heatmaps& h, const cv::Mat& values, double max_value,
                     const char* title);
cv::Mat compose_frame_figure(const cv::Mat& left_bgr, const introspection::Heatmaps& h,
                             const std::vector<LabelledCell>& cells);

}  // namespace ivoa::tools
