#include "ivoa/monitor/labeler.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ivoa/core/grid_messages.hpp"

namespace ivoa::monitor {

introspection_labels_t label_frame(const obstacle_grid_t& stereo, const obstacle_grid_t& depth) {
  const auto near = [](const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                              [](float p, float q) { return std::abs(p - q) <= kSameCellPositionM; });
  };
  const bool same_shape = stereo.num_x == depth.num_x && stereo.num_y == depth.num_y &&
                          stereo.state.size() == depth.state.size() && stereo.safety_radius == depth.safety_radius;
  if (!same_shape)
    throw LabelError("stereo grid (" + stereo.detector + ", " + std::to_string(stereo.num_x) + "x" +
                     std::to_string(stereo.num_y) + ", r=" + std::to_string(stereo.safety_radius) +
                     ") and depth grid (" + std::to_string(depth.num_x) + "x" + std::to_string(depth.num_y) +
                     ", r=" + std::to_string(depth.safety_radius) + ") have different geometry");
  if (!near(stereo.x, depth.x) || !near(stereo.y, depth.y))
    throw LabelError("stereo grid (" + stereo.detector + ") and depth grid put their cells at different positions");
  introspection_labels_t out;
  out.utime = stereo.utime;
  out.depth_utime = depth.depth_utime;
  out.detector = stereo.detector;
  out.x_min = stereo.x_min;
  out.x_max = stereo.x_max;
  out.y_min = stereo.y_min;
  out.y_max = stereo.y_max;
  out.spacing = stereo.spacing;
  out.num_x = stereo.num_x;
  out.num_y = stereo.num_y;
  out.safety_radius = stereo.safety_radius;
  out.patch_size = stereo.patch_size;
  const size_t n = stereo.state.size();
  out.label.resize(n);
  for (size_t i = 0; i < n; ++i) out.label[i] = label_of_verdicts(stereo.state[i], depth.state[i]);
  out.stereo_state = stereo.state;
  out.depth_state = depth.state;
  out.x = stereo.x;
  out.y = stereo.y;
  out.u = stereo.u;
  out.v = stereo.v;
  out.num_cells = static_cast<int32_t>(n);
  return out;
}

}  // namespace ivoa::monitor
