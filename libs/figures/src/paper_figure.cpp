#include "ivoa/figures/paper_figure.hpp"

#include <algorithm>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "ivoa/core/labels.hpp"

namespace ivoa::figures {
namespace {

constexpr int kRingRadius = 15, kDotRadius = 8;

}  // namespace

cv::Scalar class_colour(int label) {
  switch (label) {
    case 0: return {60, 180, 60};   // TP green
    case 1: return {200, 120, 30};  // TN blue
    case 2: return {0, 150, 255};   // FP orange
    case 3: return {40, 40, 220};   // FN red
    default: return {160, 160, 160};
  }
}

void draw_ring(cv::Mat& image, cv::Point at, const cv::Scalar& colour, int thickness) {
  cv::circle(image, at, kRingRadius, colour, thickness, cv::LINE_AA);
}

void draw_dot(cv::Mat& image, cv::Point at, int predicted, bool announced) {
  cv::circle(image, at, kDotRadius, class_colour(predicted), announced ? cv::FILLED : 2, cv::LINE_AA);
}

void draw_caption(cv::Mat& image, int y, int height, const std::string& text, double font_scale) {
  cv::Mat band = image(cv::Rect(0, y, image.cols, height) & cv::Rect(0, 0, image.cols, image.rows));
  band *= 0.3;
  if (text.empty()) return;
  int baseline = 0;
  const double width = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font_scale, 2, &baseline).width;
  const double scale = std::min(font_scale, font_scale * (image.cols - 24) / std::max(width, 1.0));
  cv::putText(image, text, {12, y + height - 13}, cv::FONT_HERSHEY_SIMPLEX, scale, {255, 255, 255}, 2, cv::LINE_AA);
}

void draw_caption_and_legend(cv::Mat& image, const std::string& caption) {
  draw_caption(image, 0, kCaptionHeight, caption);
  draw_caption(image, kCaptionHeight, kLegendHeight, "");
  const int middle = kCaptionHeight + kLegendHeight / 2;
  for (int k = 0, x = 12; k < 4; ++k, x += 100) {
    cv::circle(image, {x + 10, middle}, 9, class_colour(k), cv::FILLED, cv::LINE_AA);
    cv::putText(image, kLabelNames[static_cast<size_t>(k)], {x + 26, middle + 10}, cv::FONT_HERSHEY_SIMPLEX, 0.8,
                {255, 255, 255}, 2, cv::LINE_AA);
  }
}

cv::Mat blend_heatmap(const cv::Mat& left, const HeatmapGrid& grid, const cv::Mat& values, double max_value,
                      const std::string& title) {
  cv::Mat scaled, colour, up;
  values.convertTo(scaled, CV_8U, 255.0 / std::max(max_value, 1e-9));
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  // Centres of the first and last patches span cols x stride pixels.
  const int first = grid.patch_size / 2 - grid.stride / 2;
  const cv::Rect inner(first, first, grid.cols * grid.stride, grid.rows * grid.stride);
  cv::resize(colour, up, inner.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat full(left.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Rect visible = inner & cv::Rect(0, 0, left.cols, left.rows);
  if (!visible.empty()) up(cv::Rect(visible.tl() - inner.tl(), visible.size())).copyTo(full(visible));
  cv::Mat out;
  cv::addWeighted(left, 0.45, full, 0.55, 0, out);
  draw_caption(out, 0, kCaptionHeight, title);
  return out;
}

double uncertainty_scale_top(const std::vector<cv::Mat>& uncertainty_maps) {
  double top = kMinUncertaintyScale;
  for (const auto& map : uncertainty_maps) {
    double map_max = 0;
    if (!map.empty()) cv::minMaxLoc(map, nullptr, &map_max);
    top = std::max(top, map_max);
  }
  return top;
}

cv::Mat uncertainty_panel(const cv::Mat& left, const HeatmapGrid& grid, const cv::Mat& uncertainty, double scale_max,
                          const std::string& shared_note) {
  const bool own_scale = scale_max <= 0;
  if (own_scale) scale_max = uncertainty_scale_top({uncertainty});
  char scale[32];
  std::snprintf(scale, sizeof(scale), "%.3f", scale_max);
  const std::string note = own_scale ? " (this frame)" : shared_note;
  return blend_heatmap(left, grid, uncertainty, scale_max,
                       "uncertainty (class variance): 0 .. " + std::string(scale) + note);
}

}  // namespace ivoa::figures
