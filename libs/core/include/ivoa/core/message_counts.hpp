#pragma once
// LCM's encode() trusts a message's length fields: a count that disagrees
// with its vector overflows the buffer. Bus::publish() calls set_counts()
// on every message, so length fields are always derived from the vectors.
// Parallel arrays of one count must have equal sizes; a mismatch is a
// programming error and throws std::logic_error naming the field.
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/introspection_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/process_status_t.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa {

void set_counts(image_t& msg);
void set_counts(stereo_image_t& msg);
void set_counts(depth_image_t& msg);
void set_counts(camera_intrinsics_t& msg);
void set_counts(rig_calibration_t& msg);
void set_counts(obstacle_grid_t& msg);
void set_counts(introspection_labels_t& msg);
void set_counts(introspection_t& msg);
void set_counts(process_status_t& msg);
void set_counts(sim_ground_truth_t& msg);

}  // namespace ivoa
