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
  int patch_side = 0;     // the square the model sees around (u, v), pixels
  int stereo_state = -1;  // the detector's verdict recorded for the cell (obstacle_grid_t.STATE_*)
};

// Sets each cell's dot from its prediction (cells and predictions in the
// same order). given_verdict: where the cell has a recorded verdict (free or
// obstacle), the prediction given it, gated at verdict_threshold, as the live
// process makes it; cells without one keep the prediction from the image.
void set_predictions(std::vector<LabelledCell>& cells, const std::vector<introspection::Prediction>& predictions,
                     bool given_verdict, double verdict_threshold);

// The left image with each cell's ring (label) and dot (prediction);
// dots_given_verdict only changes the caption (set_predictions fills the dots).
cv::Mat draw_grid(const cv::Mat& left_bgr, const std::vector<LabelledCell>& cells, bool dots_given_verdict = false);
// uncertainty_max: the top of the uncertainty panel's colour scale (class
// variance), shared by every figure of a run so that they compare; <= 0:
// this frame's own top (figures::uncertainty_panel), as the paper's
// figures are drawn.
cv::Mat compose_frame_figure(const cv::Mat& left_bgr, const introspection::Heatmaps& h,
                             const std::vector<LabelledCell>& cells, bool dots_given_verdict = false,
                             double uncertainty_max = 0);

}  // namespace ivoa::tools
