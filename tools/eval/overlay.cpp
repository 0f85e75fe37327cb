#include "overlay.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "ivoa/figures/paper_figure.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::tools {

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

cv::Mat draw_grid(const cv::Mat& left, const std::vector<LabelledCell>& cells, bool dots_given_verdict) {
  cv::Mat out = left.clone();
  for (const auto& c : cells) {
    const cv::Point p(cvRound(c.u), cvRound(c.v));
    if (c.label >= 0) figures::draw_ring(out, p, figures::class_colour(c.label), 4);
    if (c.predicted >= 0) figures::draw_dot(out, p, c.predicted, c.announced);
  }
  figures::draw_caption_and_legend(out, dots_given_verdict
                                            ? "ring: label   dot: prediction given the verdict (hollow: withheld)"
                                            : "ring: label   dot: prediction (hollow: withheld)");
  return out;
}

cv::Mat compose_frame_figure(const cv::Mat& left, const introspection::Heatmaps& h,
                             const std::vector<LabelledCell>& cells, bool dots_given_verdict, double uncertainty_max) {
  const cv::Mat failure = h.probability[2] + h.probability[3];
  const figures::HeatmapGrid grid{h.rows, h.cols, h.stride, h.patch_size};
  const cv::Mat a = draw_grid(left, cells, dots_given_verdict);
  const cv::Mat b = figures::blend_heatmap(left, grid, failure, 1.0, "P(FP) + P(FN): 0 blue .. 1 red");
  const cv::Mat c = figures::uncertainty_panel(left, grid, h.uncertainty, uncertainty_max, " (every overlay)");
  cv::Mat row;
  cv::hconcat(std::vector<cv::Mat>{a, b, c}, row);
  return row;
}

}  // namespace ivoa::tools
