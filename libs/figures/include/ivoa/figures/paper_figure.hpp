#pragma once
// Pieces of the per-frame figures drawn like the IVOA paper's: class
// colours, the ring (label) and dot (prediction) of a ground cell, caption
// bands with the class legend, and a heatmap blended over the left image.
// ivoa-viewer and ivoa-eval compose their figures from these.
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace ivoa::figures {

inline constexpr int kCaptionHeight = 44;  // rows of the top caption band
inline constexpr int kLegendHeight = 36;   // rows of the class legend under it

// BGR colours of the classes (0 TP green, 1 TN blue, 2 FP orange, 3 FN red;
// anything else grey), as in the reference code's figures.
cv::Scalar class_colour(int label);

// An outer ring (label or verdict) and an inner dot (prediction: filled when
// announced, an outline when withheld for its uncertainty) at a cell.
void draw_ring(cv::Mat& image, cv::Point at, const cv::Scalar& colour, int thickness);
void draw_dot(cv::Mat& image, cv::Point at, int predicted, bool announced);

// A darkened band over rows [y, y + height) with white text on it, so text
// stays readable on any image; text too long for the width is set smaller.
void draw_caption(cv::Mat& image, int y, int height, const std::string& text, double font_scale = 0.8);

// The caption band at the top with the text, and under it a swatch and
// name for each of the four classes.
void draw_caption_and_legend(cv::Mat& image, const std::string& caption);

// Where a heatmap lies on the image: cell (r, c) is the patch at
// (c * stride, r * stride), patch_size square.
struct HeatmapGrid {
  int rows = 0, cols = 0, stride = 0, patch_size = 0;
};

// values (rows x cols, CV_32F, 0 .. max_value) coloured blue .. red, each at
// its patch centre and interpolated between centres, blended over the
// image, with the title in a caption band. Parts outside the image are cut.
cv::Mat blend_heatmap(const cv::Mat& left_bgr, const HeatmapGrid& grid, const cv::Mat& values, double max_value,
                      const std::string& title);

// The floor of an uncertainty colour scale taken from the data: a frame
// the model is sure of everywhere is not stretched to look unsure.
inline constexpr double kMinUncertaintyScale = 0.01;

// The top of a colour scale the uncertainty maps (class variance) of one or
// more frames share: the largest value any shows, at least kMinUncertaintyScale.
double uncertainty_scale_top(const std::vector<cv::Mat>& uncertainty_maps);

// The uncertainty heatmap panel on the scale 0 .. scale_max, which its title
// gives; scale_max <= 0: this frame's own top (the paper's figures), said
// "(this frame)"; otherwise `shared_note` follows the scale in the title.
cv::Mat uncertainty_panel(const cv::Mat& left_bgr, const HeatmapGrid& grid, const cv::Mat& uncertainty,
                          double scale_max, const std::string& shared_note = "");

}  // namespace ivoa::figures
