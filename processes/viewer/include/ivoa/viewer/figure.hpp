#pragma once
// The viewer's per-frame figure, drawn like the IVOA paper's figures (and
// ivoa-eval's overlays): three panels side by side,
//   1. the left image with the ground query grid: outer ring = the label
//      (stereo verdict vs depth verdict, Algorithm 1) or, without depth, the
//      stereo verdict; inner dot = the introspection prediction (hollow when
//      withheld for its uncertainty), from the image alone (the paper's) or
//      given the detector's verdict. TP green, TN blue, FP orange, FN red.
//   2. the failure heatmap P(FP) + P(FN), 0 blue .. 1 red;
//   3. the uncertainty heatmap.
// Whatever the frame lacks is left out and said so on the figure.
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/viewer/frame_matcher.hpp"

namespace ivoa::viewer {

struct FigureOptions {
  double scale = 0.5;  // figure panels relative to the image size
  // Dots: the prediction given the detector's verdict of the frame where
  // the message has it (else the image-alone one), instead of the paper's
  // image-alone prediction.
  bool dots_given_verdict = false;
  // Top of the uncertainty panel's colour scale (class variance); 0: each
  // frame's own maximum, as the paper's figures (a stream then flickers).
  double uncertainty_max = 0;
};

// What the grid panel draws at one cell.
struct CellMark {
  float u = 0, v = 0;
  int ring_label = -1;      // introspection_labels_t.LABEL_* (TP 0, TN 1, FP 2, FN 3); -1 none
  int ring_verdict = -1;    // obstacle_grid_t.STATE_* when only one grid judged the cell; -1 none
  bool none_label = false;  // the labeller could not judge the cell (LABEL_NONE)
};
struct PredictionMark {
  float u = 0, v = 0;
  int predicted = -1;
  bool announced = true;
};

// Rings from the labels if the frame has them, else Algorithm 1 on the
// frame's stereo and depth grids, else the one grid's verdicts.
std::vector<CellMark> cell_marks(const FrameSet& frame);
std::vector<PredictionMark> prediction_marks(const FrameSet& frame, bool given_verdict = false);

// Empty if the message can be drawn, else what is wrong with it.
std::string check_introspection(const introspection_t& msg);

// BGR colours of verdicts (free, obstacle, unknown); the classes' are
// figures::class_colour.
cv::Scalar verdict_colour(int state);

// The three-panel figure; its size depends only on the image size and scale.
cv::Mat draw_frame_figure(const cv::Mat& left_bgr, const FrameSet& frame, const FigureOptions& options = {});

}  // namespace ivoa::viewer
