#include "live_score.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/introspection_content.hpp"

namespace ivoa::tools {
namespace {

bool is_class(int c) { return c >= 0 && c < LabelConfusion::kLabels; }

// Labels and queries come from grids of the same geometry: a cell is the
// same cell when its position agrees to the millimetre.
std::pair<long, long> cell_key(float x, float y) { return {std::lround(x * 1000.0f), std::lround(y * 1000.0f)}; }

// Grid cells lie near the robot; beyond this (metres) a position is a
// damaged message, and millimetre keys would overflow.
constexpr float kMaxCellDistanceM = 1e6f;

bool sane_position(float x, float y) {
  return std::isfinite(x) && std::isfinite(y) && std::abs(x) <= kMaxCellDistanceM && std::abs(y) <= kMaxCellDistanceM;
}

}  // namespace

std::string LiveScorer::add(const introspection_labels_t& m) {
  if (std::string why = labels_content_error(m); !why.empty()) return why;
  for (int i = 0; i < m.num_cells; ++i)
    if (!sane_position(m.x[i], m.y[i])) return "cell " + std::to_string(i) + ": position is over 1000 km away";
  detectors_.insert(m.detector);
  repeated_messages_ += labels_.count(m.utime);
  auto& cells = labels_[m.utime];
  cells.clear();  // a repeated frame counts once, with its latest labels
  for (int i = 0; i < m.num_cells; ++i)
    if (is_class(m.label[i])) cells.push_back({m.x[i], m.y[i], m.label[i], m.stereo_state[i]});
  return "";
}

std::string LiveScorer::add(const introspection_t& m) {
  // Over a day for one frame is no timing either (1e300 printed as 300 digits).
  if (!(std::isfinite(m.compute_ms) && m.compute_ms >= 0 && m.compute_ms <= 86'400'000))
    return fmt::format("compute_ms {:g} is no duration", m.compute_ms);
  if (std::string why = introspection_content_error(m); !why.empty()) return why;
  for (int i = 0; i < m.num_queries; ++i)
    if (!sane_position(m.query_x[i], m.query_y[i]))
      return "query " + std::to_string(i) + ": position is over 1000 km away";
  models_.insert(m.model_id);
  repeated_messages_ += predictions_.count(m.utime);
  compute_ms_[m.utime] = m.compute_ms;
  auto& queries = predictions_[m.utime];
  queries.clear();
  for (int i = 0; i < m.num_queries; ++i)
    queries.push_back({m.query_x[i], m.query_y[i], m.query_class[i], m.query_announced[i], m.query_verdict[i],
                       m.query_verdict_class[i], m.query_verdict_announced[i]});
  return "";
}

std::string LiveScorer::add(const obstacle_grid_t& m) {
  if (std::string why = grid_content_error(m); !why.empty()) return why;
  auto& outside = outside_view_[m.utime];
  outside.clear();
  for (int i = 0; i < m.num_cells; ++i)
    if (!m.in_image[i]) outside.insert(cell_key(m.x[i], m.y[i]));
  return "";
}

void LiveScorer::score_frame(int64_t utime, const std::vector<LabelledCell>& cells, const std::vector<Query>& queries,
                             LiveScore& s) const {
  std::map<std::pair<long, long>, const Query*> by_cell;
  for (const auto& q : queries) by_cell[cell_key(q.x, q.y)] = &q;
  const auto grid = outside_view_.find(utime);
  for (const auto& c : cells) {
    ++s.labelled_cells;
    const auto key = cell_key(c.x, c.y);
    const auto it = by_cell.find(key);
    if (it == by_cell.end()) {
      if (grid != outside_view_.end() && grid->second.count(key)) ++s.outside_view_cells;
      else if (queries.empty()) ++s.no_grid_cells;
      else ++s.unmatched_cells;
      continue;
    }
    const Query& q = *it->second;
    s.image.all.add(c.label, q.predicted);
    if (q.announced) s.image.announced.add(c.label, q.predicted);
    if (!is_class(q.verdict_class)) {
      ++s.verdict_unknown;
      continue;
    }
    if (q.verdict != c.stereo_state) ++s.verdict_disagrees;
    s.given_verdict.all.add(c.label, q.verdict_class);
    if (q.verdict_announced) s.given_verdict.announced.add(c.label, q.verdict_class);
  }
}

LiveScore LiveScorer::finish() const {
  LiveScore s;
  s.labelled_frames = static_cast<int64_t>(labels_.size());
  s.predicted_frames = static_cast<int64_t>(predictions_.size());
  s.repeated_messages = repeated_messages_;
  s.models = models_;
  s.detectors = detectors_;
  std::vector<double> compute_ms;
  for (const auto& [utime, ms] : compute_ms_) compute_ms.push_back(ms);
  s.compute = summarize_compute_ms(compute_ms);
  for (const auto& [utime, cells] : labels_) {
    const auto it = predictions_.find(utime);
    if (it == predictions_.end()) continue;
    ++s.scored_frames;
    score_frame(utime, cells, it->second, s);
  }
  return s;
}

ComputeTimes summarize_compute_ms(std::vector<double> ms) {
  ComputeTimes t;
  t.frames = static_cast<int64_t>(ms.size());
  if (ms.empty()) return t;
  std::sort(ms.begin(), ms.end());
  // Nearest rank: the smallest time at least that fraction of frames took no longer than.
  const auto rank = [&](double q) { return ms[static_cast<size_t>(std::ceil(q * ms.size())) - 1]; };
  t.median = rank(0.5);
  t.p90 = rank(0.9);
  t.max = ms.back();
  return t;
}

}  // namespace ivoa::tools
