#include "ivoa/core/introspection_content.hpp"

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa {
namespace {

using Labels = introspection_labels_t;

// Means over dropout passes may round a hair past 0 or 1.
constexpr float kRounding = 1e-4f;

bool is_probability(float p) { return std::isfinite(p) && p >= -kRounding && p <= 1.0f + kRounding; }
// A variance of 0 smoothed by a box filter may come out a hair under 0.
bool is_variance(float v) { return std::isfinite(v) && v >= -1e-6f; }
bool is_label(int8_t c) { return c >= Labels::LABEL_TP && c <= Labels::LABEL_FN; }
bool is_flag(int8_t f) { return f == 0 || f == 1; }

std::string heatmap_error(const introspection_t& m) {
  if (m.rows < 0 || m.cols < 0 || int64_t{m.rows} * m.cols != m.num_cells)
    return "heatmap " + std::to_string(m.rows) + "x" + std::to_string(m.cols) + " is not its " +
           std::to_string(m.num_cells) + " cells";
  const std::pair<const char*, const std::vector<float>*> probabilities[] = {
      {"prob_tp", &m.prob_tp}, {"prob_tn", &m.prob_tn}, {"prob_fp", &m.prob_fp}, {"prob_fn", &m.prob_fn}};
  const std::pair<const char*, const std::vector<float>*> variances[] = {{"uncertainty", &m.uncertainty},
                                                                         {"class_variance", &m.class_variance}};
  for (size_t i = 0; i < static_cast<size_t>(m.num_cells); ++i) {
    for (const auto& [name, values] : probabilities)
      if (!is_probability((*values)[i]))
        return "heatmap cell " + std::to_string(i) + ": " + name + " " + std::to_string((*values)[i]) +
               " is not a probability";
    for (const auto& [name, values] : variances)
      if (!is_variance((*values)[i]))
        return "heatmap cell " + std::to_string(i) + ": " + name + " " + std::to_string((*values)[i]) +
               " is not a variance";
  }
  return "";
}

std::string query_error(const introspection_t& m, size_t i) {
  const std::string query = "query " + std::to_string(i) + ": ";
  if (!std::isfinite(m.query_x[i]) || !std::isfinite(m.query_y[i])) return query + "position is not finite";
  // The viewer drew a NaN pixel, a probability of 7 and a variance of -5.
  if (!pixel_in_some_image(m.query_u[i], m.query_v[i]))
    return query + "pixel (" + std::to_string(m.query_u[i]) + ", " + std::to_string(m.query_v[i]) +
           ") lies outside any image";
  if (!is_label(m.query_class[i]))
    return query + "class " + std::to_string(m.query_class[i]) + " is none of TP 0, TN 1, FP 2, FN 3";
  if (!is_probability(m.query_probability[i]))
    return query + "probability " + std::to_string(m.query_probability[i]) + " is not a probability";
  if (!is_variance(m.query_uncertainty[i]))
    return query + "uncertainty " + std::to_string(m.query_uncertainty[i]) + " is not a variance";
  if (!is_flag(m.query_announced[i]) || !is_flag(m.query_verdict_announced[i]))
    return query + "announced flags (" + std::to_string(m.query_announced[i]) + ", " +
           std::to_string(m.query_verdict_announced[i]) + ") are not 0 or 1";
  const int8_t v = m.query_verdict[i];
  if (v != obstacle_grid_t::STATE_FREE && v != obstacle_grid_t::STATE_OBSTACLE && v != obstacle_grid_t::STATE_UNKNOWN)
    return query + "verdict " + std::to_string(v) + " is none of FREE 0, OBSTACLE 1, UNKNOWN 2";
  if (!is_label(m.query_verdict_class[i]) && m.query_verdict_class[i] != Labels::LABEL_NONE)
    return query + "class given the verdict " + std::to_string(m.query_verdict_class[i]) + " is none of -1..3";
  // NaN where the verdict is unknown, as the message's comments say.
  const bool known = m.query_verdict_class[i] != Labels::LABEL_NONE;
  if (known && !(is_probability(m.query_p_wrong[i]) && is_variance(m.query_p_wrong_variance[i])))
    return query + "P(wrong) " + std::to_string(m.query_p_wrong[i]) + " with variance " +
           std::to_string(m.query_p_wrong_variance[i]) + " is not a probability and a variance";
  return "";
}

}  // namespace

std::string introspection_content_error(const introspection_t& m) {
  if (std::string error = heatmap_error(m); !error.empty()) return error;
  if (m.num_queries < 0) return "num_queries " + std::to_string(m.num_queries) + " is negative";
  for (size_t i = 0; i < static_cast<size_t>(m.num_queries); ++i)
    if (std::string error = query_error(m, i); !error.empty()) return error;
  return "";
}

}  // namespace ivoa
