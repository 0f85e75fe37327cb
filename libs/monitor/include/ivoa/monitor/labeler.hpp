#pragma once
// Algorithm 1 of the IVOA paper over a frame: each query cell labelled by
// comparing the stereo detector's verdict with the depth monitor's
// (per cell: ivoa::label_of_verdicts, core/grid_messages.hpp, which the
// readers of recorded labels check them with).
#include <stdexcept>

#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::monitor {

class LabelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Labels one frame. The two grids must have the same geometry (else
// LabelError says what differs). utime is the stereo frame's.
introspection_labels_t label_frame(const obstacle_grid_t& stereo, const obstacle_grid_t& depth);

}  // namespace ivoa::monitor
