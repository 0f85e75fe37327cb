#include "ivoa/viewer/figure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/figures/paper_figure.hpp"

namespace ivoa::viewer {
namespace {

bool drawable(float u, float v, const cv::Size& size) {
  return std::isfinite(u) && std::isfinite(v) && u >= 0 && v >= 0 && u < size.width && v < size.height;
}

void draw_marks(cv::Mat& out, const std::vector<CellMark>& cells, const std::vector<PredictionMark>& predictions) {
  for (const auto& c : cells) {
    if (!drawable(c.u, c.v, out.size())) continue;
    const cv::Point p(cvRound(c.u), cvRound(c.v));
    if (c.ring_label >= 0) figures::draw_ring(out, p, figures::class_colour(c.ring_label), 4);
    else if (c.ring_verdict >= 0) figures::draw_ring(out, p, verdict_colour(c.ring_verdict), 3);
    else if (c.none_label) figures::draw_ring(out, p, verdict_colour(obstacle_grid_t::STATE_UNKNOWN), 1);
  }
  for (const auto& d : predictions)
    if (drawable(d.u, d.v, out.size()) && d.predicted >= 0)
      figures::draw_dot(out, {cvRound(d.u), cvRound(d.v)}, d.predicted, d.announced);
}

std::string legend_caption(bool verdict_rings, bool dots_given_verdict) {
  const std::string rings =
      verdict_rings ? "ring: stereo verdict (white free, magenta obstacle)" : "ring: label (stereo vs depth)";
  const std::string dots = dots_given_verdict ? "dot: prediction given the verdict (hollow: withheld)"
                                              : "dot: prediction (hollow: withheld)";
  return rings + "   " + dots;
}

std::string status_line(const FrameSet& f) {
  char text[320];
  int n = std::snprintf(text, sizeof(text), "t %.3f", static_cast<double>(f.utime) * 1e-6);
  auto add = [&](const char* fmt, auto... args) {
    if (n < static_cast<int>(sizeof(text)))
      n += std::snprintf(text + n, sizeof(text) - static_cast<size_t>(n), fmt, args...);
  };
  if (f.stereo) add("  stereo %s %.0f ms", f.stereo->detector.c_str(), f.stereo->compute_ms);
  if (f.labels) {
    int counts[4] = {0, 0, 0, 0};
    for (auto l : f.labels->label)
      if (l >= 0 && l < 4) ++counts[l];
    add("  TP %d TN %d FP %d FN %d", counts[0], counts[1], counts[2], counts[3]);
  }
  if (f.introspection) add("  CNN T=%d %.0f ms", f.introspection->mc_passes, f.introspection->compute_ms);
  for (Part p : {kStereoGrid, kDepthGrid, kLabels, kIntrospection})
    if (!f.has(p)) add("  no %s", part_name(p));
  return text;
}

cv::Mat missing_panel(const cv::Mat& left, const std::string& title, const std::string& why) {
  cv::Mat out = left * 0.25;
  figures::draw_caption(out, 0, figures::kCaptionHeight, title);
  cv::putText(out, why, {24, out.rows / 2}, cv::FONT_HERSHEY_SIMPLEX, 1.0, {255, 255, 255}, 2, cv::LINE_AA);
  return out;
}

cv::Mat heatmap_of(const introspection_t& h, const std::vector<float>& a, const std::vector<float>* b = nullptr) {
  cv::Mat m(h.rows, h.cols, CV_32F);
  for (int i = 0; i < h.num_cells; ++i)
    m.at<float>(i / h.cols, i % h.cols) = a[static_cast<size_t>(i)] + (b ? (*b)[static_cast<size_t>(i)] : 0.0f);
  return m;
}

}  // namespace

cv::Scalar verdict_colour(int state) {
  switch (state) {
    case obstacle_grid_t::STATE_FREE: return {255, 255, 255};
    case obstacle_grid_t::STATE_OBSTACLE: return {255, 0, 255};
    default: return {140, 140, 140};
  }
}

std::vector<CellMark> cell_marks(const FrameSet& f) {
  std::vector<CellMark> out;
  if (f.labels) {
    const auto& l = *f.labels;
    for (int i = 0; i < l.num_cells; ++i) {
      CellMark m{l.u[static_cast<size_t>(i)], l.v[static_cast<size_t>(i)], l.label[static_cast<size_t>(i)], -1, false};
      m.none_label = m.ring_label < 0;
      out.push_back(m);
    }
    return out;
  }
  const obstacle_grid_t* one = f.stereo ? &*f.stereo : f.depth ? &*f.depth : nullptr;
  if (!one) return out;
  const bool both = f.stereo && f.depth && f.stereo->num_cells == f.depth->num_cells;
  for (size_t i = 0; i < static_cast<size_t>(one->num_cells); ++i) {
    if (!one->in_image[i]) continue;
    CellMark m{one->u[i], one->v[i], -1, -1, false};
    if (both) {
      m.ring_label = label_of_verdicts(f.stereo->state[i], f.depth->state[i]);
      m.none_label = m.ring_label < 0;
    } else {
      m.ring_verdict = one->state[i];
    }
    out.push_back(m);
  }
  return out;
}

std::vector<PredictionMark> prediction_marks(const FrameSet& f, bool given_verdict) {
  std::vector<PredictionMark> out;
  if (!f.introspection) return out;
  const auto& h = *f.introspection;
  for (size_t i = 0; i < static_cast<size_t>(h.num_queries); ++i) {
    if (given_verdict && h.query_verdict_class[i] >= 0)
      out.push_back({h.query_u[i], h.query_v[i], h.query_verdict_class[i], h.query_verdict_announced[i] != 0});
    else out.push_back({h.query_u[i], h.query_v[i], h.query_class[i], h.query_announced[i] != 0});
  }
  return out;
}

std::string check_introspection(const introspection_t& h) {
  if (h.rows <= 0 || h.cols <= 0 || h.stride <= 0 || h.patch_size <= 0)
    return "heatmap geometry " + std::to_string(h.rows) + "x" + std::to_string(h.cols) + ", stride " +
           std::to_string(h.stride) + ", patch " + std::to_string(h.patch_size) + " is not drawable";
  if (static_cast<int64_t>(h.rows) * h.cols != h.num_cells)
    return "heatmap " + std::to_string(h.rows) + "x" + std::to_string(h.cols) + " but " + std::to_string(h.num_cells) +
           " cells";
  // The model's patches lie inside the image: a heatmap reaching past it is not of this image.
  const int64_t width = int64_t{h.cols - 1} * h.stride + h.patch_size;
  const int64_t height = int64_t{h.rows - 1} * h.stride + h.patch_size;
  // One row or column passes the check above with any stride, and the
  // heatmap is drawn over cols x stride pixels (a stride of 1e5 asked 30 GB).
  if (width > h.image_width || height > h.image_height || h.stride > std::max(h.image_width, h.image_height))
    return "heatmap of " + std::to_string(h.rows) + "x" + std::to_string(h.cols) + " patches of " +
           std::to_string(h.patch_size) + " px every " + std::to_string(h.stride) + " px covers " +
           std::to_string(width) + "x" + std::to_string(height) + " px, more than its " +
           std::to_string(h.image_width) + "x" + std::to_string(h.image_height) + " image";
  return "";
}

cv::Mat draw_frame_figure(const cv::Mat& left, const FrameSet& f, const FigureOptions& options) {
  const auto cells = cell_marks(f);
  cv::Mat grid = left.clone();
  draw_marks(grid, cells, prediction_marks(f, options.dots_given_verdict));
  const bool verdict_rings = !cells.empty() && cells.front().ring_verdict >= 0;
  figures::draw_caption_and_legend(grid, legend_caption(verdict_rings, options.dots_given_verdict));
  figures::draw_caption(grid, grid.rows - 40, 40, status_line(f), 0.7);

  cv::Mat failure, uncertainty;
  const std::string failure_title = "P(FP) + P(FN): 0 blue .. 1 red";
  std::string problem = f.introspection ? check_introspection(*f.introspection) : "no INTROSPECTION for this frame";
  if (problem.empty() && (f.introspection->image_width != left.cols || f.introspection->image_height != left.rows))
    problem = "INTROSPECTION is for a " + std::to_string(f.introspection->image_width) + "x" +
              std::to_string(f.introspection->image_height) + " image";
  if (problem.empty()) {
    const auto& h = *f.introspection;
    const cv::Mat u = heatmap_of(h, h.uncertainty);
    const figures::HeatmapGrid cells_at{h.rows, h.cols, h.stride, h.patch_size};
    failure = figures::blend_heatmap(left, cells_at, heatmap_of(h, h.prob_fp, &h.prob_fn), 1.0, failure_title);
    uncertainty = figures::uncertainty_panel(left, cells_at, u, options.uncertainty_max);
  } else {
    failure = missing_panel(left, failure_title, problem);
    uncertainty = missing_panel(left, "uncertainty", problem);
  }
  cv::Mat row;
  cv::hconcat(std::vector<cv::Mat>{grid, failure, uncertainty}, row);
  if (options.scale > 0 && options.scale != 1.0)
    cv::resize(row, row, cv::Size(), options.scale, options.scale, cv::INTER_AREA);
  return row;
}

}  // namespace ivoa::viewer
