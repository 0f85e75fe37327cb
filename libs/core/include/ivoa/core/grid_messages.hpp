#pragma once
// The query grid as carried by obstacle_grid_t and introspection_labels_t:
// building messages from a QueryGrid, and checking that a received grid has
// the geometry a process was configured with.
#include <cmath>
#include <string>

#include "ivoa/core/query_grid.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace CLI {
class App;
}

namespace ivoa {

// Adds --grid-x-min ... --safety-radius, --patch-size flags for `config`.
void add_query_grid_options(CLI::App& app, QueryGridConfig& config);

// An obstacle grid for `grid` with every cell UNKNOWN.
obstacle_grid_t make_obstacle_grid(const QueryGrid& grid, const std::string& detector, int64_t utime);

// Empty if a received grid's cells can be used, otherwise the first thing
// wrong: arrays not num_cells long, a state none of STATE_*, a position that
// is not finite, or a cell in_image whose pixel is not finite or lies
// outside any image (SHRT_MAX a side).
std::string grid_content_error(const obstacle_grid_t& msg);

// Whether (u, v) can be a pixel of some calibrated image (none is SHRT_MAX a
// side): a cell "in view" at pixel 1e9 was predicted at, labelled and drawn.
bool pixel_in_some_image(float u, float v);

// The same for a labels message: a grid geometry or safety radius that is
// not a finite distance, num_x by num_y not its cells, a label none of LABEL_*, a position not finite, a
// labelled cell's pixel outside any image, a verdict none of STATE_*, or a label its two verdicts do not give.
std::string labels_content_error(const introspection_labels_t& msg);

// Algorithm 1 of the IVOA paper, the label of a cell from the stereo
// detector's verdict and the depth monitor's (O = "obstacle free"):
//   O_M &  O_S -> TN      O_M & !O_S -> FP
//  !O_M &  O_S -> FN     !O_M & !O_S -> TP
// and LABEL_NONE for a cell either could not judge (UNKNOWN).
int8_t label_of_verdicts(int8_t stereo_state, int8_t depth_state);

// Cell positions are floats made from the same doubles on every machine,
// but a compiler may round a last bit differently: 0.1 mm is "the same".
constexpr double kSameCellPositionM = 1e-4;

// Copies the geometry fields shared by obstacle_grid_t and introspection_labels_t.
template <class Msg>
void set_geometry(Msg& msg, const QueryGridConfig& c, int num_x, int num_y) {
  msg.x_min = c.x_min;
  msg.x_max = c.x_max;
  msg.y_min = c.y_min;
  msg.y_max = c.y_max;
  msg.spacing = c.spacing;
  msg.num_x = num_x;
  msg.num_y = num_y;
  msg.safety_radius = c.safety_radius;
  msg.patch_size = c.patch_size;
}

template <class Msg>
QueryGridConfig geometry_of(const Msg& msg) {
  QueryGridConfig c;
  c.x_min = msg.x_min;
  c.x_max = msg.x_max;
  c.y_min = msg.y_min;
  c.y_max = msg.y_max;
  c.spacing = msg.spacing;
  c.safety_radius = msg.safety_radius;
  c.patch_size = msg.patch_size;
  return c;
}

// Empty if `msg` has the geometry of `grid`, otherwise what differs.
template <class Msg>
std::string geometry_mismatch(const Msg& msg, const QueryGrid& grid) {
  const QueryGridConfig& c = grid.config();
  auto near = [](double a, double b) { return std::abs(a - b) < 1e-6; };
  if (msg.num_x != grid.num_x() || msg.num_y != grid.num_y() || msg.num_cells != grid.size())
    return "grid is " + std::to_string(msg.num_x) + "x" + std::to_string(msg.num_y) + " (" +
           std::to_string(msg.num_cells) + " cells), configured " + std::to_string(grid.num_x()) + "x" +
           std::to_string(grid.num_y());
  if (!near(msg.x_min, c.x_min) || !near(msg.x_max, c.x_max) || !near(msg.y_min, c.y_min) ||
      !near(msg.y_max, c.y_max) || !near(msg.spacing, c.spacing))
    return "grid extents or spacing differ from the configured grid";
  if (!near(msg.safety_radius, c.safety_radius))
    return "safety radius " + std::to_string(msg.safety_radius) + " m, configured " + std::to_string(c.safety_radius) +
           " m";
  if (msg.x.size() != grid.cells().size() || msg.y.size() != grid.cells().size())
    return "the cell positions are " + std::to_string(msg.x.size()) + " and " + std::to_string(msg.y.size()) +
           " long, the grid has " + std::to_string(grid.size()) + " cells";
  for (size_t i = 0; i < grid.cells().size(); ++i) {
    const QueryCell& cell = grid.cells()[i];
    if (!(std::abs(msg.x[i] - cell.x) <= kSameCellPositionM && std::abs(msg.y[i] - cell.y) <= kSameCellPositionM))
      return "cell " + std::to_string(i) + " is at (" + std::to_string(msg.x[i]) + ", " + std::to_string(msg.y[i]) +
             ") m, the configured grid's at (" + std::to_string(cell.x) + ", " + std::to_string(cell.y) + ") m";
  }
  return "";
}

}  // namespace ivoa
