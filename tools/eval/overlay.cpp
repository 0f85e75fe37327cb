#include "overlay.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::tools {

cv::Scalar class_colour(int label) {
  switch (label) {
    case 0: return {60, 180, 60};    // TP green
    case 1: return {200, 120, 30};   // TN blue
    case 2: return {0, 150, 255};    // FP orange
    case 3: return {40, 40, 220};    // FN red
    default: return {160, 160, 160};
  }
}

void set_predictions(std::vector<LabelledCell>& cells, const std::vector<introspection::Prediction>& predictions,
                     bool given_verdict, double verdict_threshold) {
  if (predictions.size() != cells.size())
    throw std::invalid_argument("set_predictions: " + std::to_string(predictions.size()) + " predictions for " +
                                std::to_string(cells.size()) + " cells");
  for (size_t i = 0; i < cells.size(); ++i) {
    LabelledCell& cell = cells[i];
    cell.predicted = predictions[i].predicted;
    cell.announced = predictions[i].announced;
    const bool obstacle = cell.stereo_state == obstacle_grid_t::STATE_OBSTACLE;
    if (!given_verdict || (!obstacle && cell.stereo_state != obstacle_grid_t::STATE_FREE)) continue;
    const auto v = introspection::given_verdict(predictions[i], obstacle, verdict_threshold);
    cell.predicted = v.predicted;
    cell.announced = v.announced;
  }
}

namespace {

// A dark band across the top so titles stay readable on any image; long
// titles are set smaller to fit the width.
void banner(cv::Mat& image, const std::string& text) {
  cv::Mat band = image(cv::Rect(0, 0, image.cols, 44));
  band *= 0.35;
  int baseline = 0;
  const double width = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.95, 2, &baseline).width;
  const double scale = std::min(0.95, 0.95 * (image.cols - 24) / std::max(width, 1.0));
  cv::putText(image, text, {12, 31}, cv::FONT_HERSHEY_SIMPLEX, scale, {255, 255, 255}, 2, cv::LINE_AA);
}

}  // namespace

cv::Mat draw_grid(const cv::Mat& left, const std::vector<LabelledCell>& cells, bool dots_given_verdict) {
  cv::Mat out = left.clone();
  for (const auto& c : cells) {
    const cv::Point p(cvRound(c.u), cvRound(c.v));
    if (c.label >= 0) cv::circle(out, p, 15, class_colour(c.label), 4, cv::LINE_AA);
    if (c.predicted >= 0) {
      if (c.announced) cv::circle(out, p, 8, class_colour(c.predicted), cv::FILLED, cv::LINE_AA);
      else cv::circle(out, p, 8, class_colour(c.predicted), 2, cv::LINE_AA);  // withheld: hollow
    }
  }
  banner(out, dots_given_verdict ? "ring: label   dot: prediction given the verdict (hollow: withheld)"
                                 : "ring: label   dot: prediction (hollow: withheld)");
  int x = 12;
  cv::Mat legend = out(cv::Rect(0, 44, out.cols, 36));
  legend *= 0.35;
  for (int k = 0; k < 4; ++k) {
    static const char* names[] = {"TP", "TN", "FP", "FN"};
    cv::circle(out, {x + 10, 62}, 9, class_colour(k), cv::FILLED, cv::LINE_AA);
    cv::putText(out, names[k], {x + 26, 72}, cv::FONT_HERSHEY_SIMPLEX, 0.85, {255, 255, 255}, 2, cv::LINE_AA);
    x += 100;
  }
  return out;
}

cv::Mat draw_heatmap(const cv::Mat& left, const introspection::Heatmaps& h, const cv::Mat& values, double max_value,
                     const char* title) {
  // Cell (r, c) covers the patch at (c * stride, r * stride); place each
  // value at its patch centre and interpolate between centres.
  cv::Mat scaled;
  values.convertTo(scaled, CV_8U, 255.0 / std::max(max_value, 1e-9));
  cv::Mat colour;
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  cv::Mat full(left.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Rect inner(h.patch_size / 2 - h.stride / 2, h.patch_size / 2 - h.stride / 2, h.cols * h.stride, h.rows * h.stride);
  cv::Mat up;
  cv::resize(colour, up, inner.size(), 0, 0, cv::INTER_LINEAR);
  up.copyTo(full(inner & cv::Rect(0, 0, left.cols, left.rows)));
  cv::Mat out;
  cv::addWeighted(left, 0.45, full, 0.55, 0, out);
  banner(out, title);
  return out;
}

cv::Mat compose_frame_figure(const cv::Mat& left, const introspection::Heatmaps& h,
                             const std::vector<LabelledCell>& cells, bool dots_given_verdict) {
  const cv::Mat failure = h.probability[2] + h.probability[3];
  double max_unc = 0;
  cv::minMaxLoc(h.uncertainty, nullptr, &max_unc);
  const cv::Mat a = draw_grid(left, cells, dots_given_verdict);
  const cv::Mat b = draw_heatmap(left, h, failure, 1.0, "P(FP) + P(FN): 0 blue .. 1 red");
  char title[96];
  std::snprintf(title, sizeof(title), "uncertainty (class variance): 0 .. %.3f", std::max(max_unc, 0.01));
  const cv::Mat c = draw_heatmap(left, h, h.uncertainty, std::max(max_unc, 0.01), title);
  cv::Mat row;
  cv::hconcat(std::vector<cv::Mat>{a, b, c}, row);
  return row;
}

}  // namespace ivoa::tools
