#pragma once
// Algorithm 1 of the IVOA paper: label each query cell by comparing the
// stereo detector's verdict with the depth monitor's. O = "obstacle free":
//   O_M &  O_S -> TN      O_M & !O_S -> FP
//  !O_M &  O_S -> FN     !O_M & !O_S -> TP
// A cell either side could not judge (UNKNOWN) gets LABEL_NONE.
#include <stdexcept>

#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::monitor {

int8_t label_for(int8_t stereo_state, int8_t depth_state);  // ivoa::label_of_verdicts, which readers check with

class LabelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Labels one frame. The two grids must have the same geometry (else
// LabelError says what differs). utime is the stereo frame's.
introspection_labels_t label_frame(const obstacle_grid_t& stereo, const obstacle_grid_t& depth);

}  // namespace ivoa::monitor
