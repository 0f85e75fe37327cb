#include "ivoa/core/message_counts.hpp"

#include <stdexcept>
#include <string>

namespace ivoa {
namespace {

// Returns the common size of parallel arrays, or throws naming the first
// array whose size differs.
template <class First, class... Rest>
int32_t common_size(const char* type, const First& first, const Rest&... rest) {
  const size_t n = first.size();
  size_t index = 0;
  auto check = [&](const auto& v) {
    ++index;
    if (v.size() != n)
      throw std::logic_error(std::string(type) + ": parallel array #" + std::to_string(index) + " has " +
                             std::to_string(v.size()) + " elements, expected " + std::to_string(n));
  };
  (check(rest), ...);
  return static_cast<int32_t>(n);
}

}  // namespace

void set_counts(image_t& msg) { msg.size = static_cast<int32_t>(msg.data.size()); }

void set_counts(stereo_image_t& msg) {
  set_counts(msg.left);
  set_counts(msg.right);
}

void set_counts(depth_image_t& msg) { msg.size = static_cast<int32_t>(msg.data.size()); }

void set_counts(camera_intrinsics_t&) {}

void set_counts(rig_calibration_t&) {}

void set_counts(obstacle_grid_t& m) {
  m.num_cells = common_size("obstacle_grid_t", m.state, m.x, m.y, m.u, m.v, m.in_image);
}

void set_counts(introspection_labels_t& m) {
  m.num_cells = common_size("introspection_labels_t", m.label, m.stereo_state, m.depth_state, m.x, m.y, m.u, m.v);
}

void set_counts(introspection_t& m) {
  m.num_cells = common_size("introspection_t heatmaps", m.prob_tp, m.prob_tn, m.prob_fp, m.prob_fn, m.uncertainty,
                            m.class_variance);
  m.num_queries =
      common_size("introspection_t queries", m.query_x, m.query_y, m.query_u, m.query_v, m.query_class,
                  m.query_probability, m.query_uncertainty, m.query_announced, m.query_verdict, m.query_verdict_class,
                  m.query_p_wrong, m.query_p_wrong_variance, m.query_verdict_announced);
}

void set_counts(process_status_t& m) {
  m.num_counters = common_size("process_status_t counters", m.counter_names, m.counter_values);
}

void set_counts(sim_ground_truth_t& m) {
  set_counts(m.surface);
  set_counts(m.phenomena);
}

}  // namespace ivoa
