#include "ivoa/core/grid_messages.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iterator>
#include <tuple>
#include <utility>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "ivoa/core/flag_checks.hpp"

namespace ivoa {

void add_query_grid_options(CLI::App& app, QueryGridConfig& c) {
  auto* g = "Query grid (robot frame, metres)";
  const std::tuple<const char*, double*, const char*> bounds[] = {
      {"--grid-x-min", &c.x_min, "nearest grid row ahead of the robot, m"},
      {"--grid-x-max", &c.x_max, "farthest grid row, m"},
      {"--grid-y-min", &c.y_min, "rightmost grid column, m"},
      {"--grid-y-max", &c.y_max, "leftmost grid column, m"}};
  for (const auto& [name, value, help] : bounds)
    app.add_option(name, *value, help)
        ->check(number_in(-kMaxGridExtentM, kMaxGridExtentM))
        ->capture_default_str()
        ->group(g);
  app.add_option("--grid-spacing", c.spacing, "distance between grid points, m")
      ->capture_default_str()
      ->check(positive_number())
      ->group(g);
  app.add_option("--safety-radius", c.safety_radius, "footprint radius r checked around each point, m")
      ->capture_default_str()
      ->check(positive_number())
      ->group(g);
  app.add_option("--patch-size", c.patch_size, "introspection patch side, pixels")
      ->capture_default_str()
      ->check(positive_number())
      ->group(g);
  // The bounds' order is known only once all of them are parsed; refused then,
  // not when the first calibration arrives.
  app.parse_complete_callback([&c] {
    if (!(c.x_min <= c.x_max)) throw CLI::ValidationError("--grid-x-min", "must be <= --grid-x-max");
    if (!(c.y_min <= c.y_max)) throw CLI::ValidationError("--grid-y-min", "must be <= --grid-y-max");
    // Every cell costs a patch per frame in a dataset and a check in each detector.
    const double cells =
        (std::floor((c.x_max - c.x_min) / c.spacing) + 1) * (std::floor((c.y_max - c.y_min) / c.spacing) + 1);
    if (cells > kMaxQueryCells)
      throw CLI::ValidationError(
          "--grid-spacing",
          fmt::format("{} m over the grid's bounds makes {:.0f} cells; at most {}", c.spacing, cells, kMaxQueryCells));
    if (c.safety_radius > kMaxSafetyRadiusM)
      throw CLI::ValidationError("--safety-radius", fmt::format("{} m: at most {} m (a robot's footprint)",
                                                                c.safety_radius, kMaxSafetyRadiusM));
  });
}

obstacle_grid_t make_obstacle_grid(const QueryGrid& grid, const std::string& detector, int64_t utime) {
  obstacle_grid_t msg;
  msg.utime = utime;
  msg.detector = detector;
  msg.depth_utime = 0;
  set_geometry(msg, grid.config(), grid.num_x(), grid.num_y());
  const size_t n = static_cast<size_t>(grid.size());
  msg.state.assign(n, obstacle_grid_t::STATE_UNKNOWN);
  msg.x.resize(n);
  msg.y.resize(n);
  msg.u.resize(n);
  msg.v.resize(n);
  msg.in_image.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const QueryCell& cell = grid.cells()[i];
    msg.x[i] = static_cast<float>(cell.x);
    msg.y[i] = static_cast<float>(cell.y);
    msg.u[i] = static_cast<float>(cell.u);
    msg.v[i] = static_cast<float>(cell.v);
    msg.in_image[i] = cell.in_image ? 1 : 0;
  }
  msg.num_cells = static_cast<int32_t>(n);
  msg.compute_ms = 0;
  return msg;
}

bool pixel_in_some_image(float u, float v) {
  const auto in_range = [](float p) { return p >= -1.0f && p <= static_cast<float>(SHRT_MAX); };
  return in_range(u) && in_range(v);
}

std::string grid_content_error(const obstacle_grid_t& msg) {
  // Cells are indexed ix * num_y + iy: a shape that is not the cells' count
  // was taken as the grid of every later frame and failed each of them.
  if (msg.num_x < 0 || msg.num_y < 0 || int64_t{msg.num_x} * msg.num_y != msg.num_cells)
    return "num_x " + std::to_string(msg.num_x) + " by num_y " + std::to_string(msg.num_y) + " is not its " +
           std::to_string(msg.num_cells) + " cells";
  const size_t n = static_cast<size_t>(std::max(msg.num_cells, 0));
  for (const auto& [name, size] : {std::pair<const char*, size_t>{"state", msg.state.size()},
                                   {"x", msg.x.size()},
                                   {"y", msg.y.size()},
                                   {"u", msg.u.size()},
                                   {"v", msg.v.size()},
                                   {"in_image", msg.in_image.size()}})
    if (size != n)
      return std::string(name) + " has " + std::to_string(size) + " entries, num_cells is " +
             std::to_string(msg.num_cells);
  for (size_t i = 0; i < n; ++i) {
    const auto where = [i] { return "cell " + std::to_string(i) + ": "; };
    const int8_t s = msg.state[i];
    if (s != obstacle_grid_t::STATE_FREE && s != obstacle_grid_t::STATE_OBSTACLE && s != obstacle_grid_t::STATE_UNKNOWN)
      return where() + "state " + std::to_string(s) + " is none of FREE 0, OBSTACLE 1, UNKNOWN 2";
    if (!std::isfinite(msg.x[i]) || !std::isfinite(msg.y[i])) return where() + "position is not finite";
    if (msg.in_image[i] && !(std::isfinite(msg.u[i]) && std::isfinite(msg.v[i])))
      return where() + "in_image, but its pixel (" + std::to_string(msg.u[i]) + ", " + std::to_string(msg.v[i]) +
             ") is not finite";
    if (msg.in_image[i] && !pixel_in_some_image(msg.u[i], msg.v[i]))
      return where() + "in_image, but its pixel (" + std::to_string(msg.u[i]) + ", " + std::to_string(msg.v[i]) +
             ") lies outside any image";
  }
  return "";
}

int8_t label_of_verdicts(int8_t stereo_state, int8_t depth_state) {
  using G = obstacle_grid_t;
  using L = introspection_labels_t;
  if (stereo_state == G::STATE_UNKNOWN || depth_state == G::STATE_UNKNOWN) return L::LABEL_NONE;
  const bool stereo_free = stereo_state == G::STATE_FREE;  // O_S
  const bool depth_free = depth_state == G::STATE_FREE;    // O_M
  if (depth_free) return stereo_free ? L::LABEL_TN : L::LABEL_FP;
  return stereo_free ? L::LABEL_FN : L::LABEL_TP;
}

namespace {

bool is_state(int8_t s) {
  return s == obstacle_grid_t::STATE_FREE || s == obstacle_grid_t::STATE_OBSTACLE ||
         s == obstacle_grid_t::STATE_UNKNOWN;
}

// Cell i's label against its two verdicts (the arrays' lengths are checked).
std::string cell_verdicts_error(const introspection_labels_t& m, size_t i) {
  const std::string cell = "cell " + std::to_string(i);
  if (!is_state(m.stereo_state[i]) || !is_state(m.depth_state[i]))
    return cell + " has verdicts (stereo " + std::to_string(m.stereo_state[i]) + ", depth " +
           std::to_string(m.depth_state[i]) + ") none of FREE 0, OBSTACLE 1, UNKNOWN 2";
  if (m.label[i] != label_of_verdicts(m.stereo_state[i], m.depth_state[i]))
    return cell + " has label " + std::to_string(m.label[i]) + ", which its verdicts (stereo " +
           std::to_string(m.stereo_state[i]) + ", depth " + std::to_string(m.depth_state[i]) + ") do not give";
  return "";
}

}  // namespace

std::string labels_content_error(const introspection_labels_t& m) {
  const double geometry[] = {m.x_min, m.x_max, m.y_min, m.y_max, m.spacing, m.safety_radius};
  if (!std::all_of(std::begin(geometry), std::end(geometry), [](double v) { return std::isfinite(v); }) ||
      m.safety_radius < 0)
    return "its grid geometry or safety radius is not a finite distance";
  if (m.num_x < 0 || m.num_y < 0 || int64_t{m.num_x} * m.num_y != m.num_cells)
    return "num_x " + std::to_string(m.num_x) + " by num_y " + std::to_string(m.num_y) + " is not its " +
           std::to_string(m.num_cells) + " cells";
  const bool has_verdicts = m.stereo_state.size() == m.label.size() && m.depth_state.size() == m.label.size();
  for (size_t i = 0; i < m.label.size(); ++i) {
    if (m.label[i] < introspection_labels_t::LABEL_NONE || m.label[i] > introspection_labels_t::LABEL_FN)
      return "cell " + std::to_string(i) + " has label " + std::to_string(m.label[i]) + ", not -1..3";
    if (!std::isfinite(m.x[i]) || !std::isfinite(m.y[i]))
      return "cell " + std::to_string(i) + " has no finite position";
    if (m.label[i] != introspection_labels_t::LABEL_NONE && !pixel_in_some_image(m.u[i], m.v[i]))
      return "cell " + std::to_string(i) + " is labelled, but its pixel (" + std::to_string(m.u[i]) + ", " +
             std::to_string(m.v[i]) + ") lies outside any image";
    if (const std::string error = has_verdicts ? cell_verdicts_error(m, i) : ""; !error.empty()) return error;
  }
  return "";
}

}  // namespace ivoa
