#pragma once
// A rendered frame as the messages a real driver publishes (stereo pair,
// depth image) plus the simulator-only ground truth.
#include <cstdint>
#include <string>

#include "ivoa/core/calibration.hpp"
#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/simulator.hpp"

namespace ivoa {
class stereo_image_t;
class depth_image_t;
class sim_ground_truth_t;
}  // namespace ivoa

namespace ivoa::sim {

inline constexpr const char* kSourceName = "simulator";

// pixelformat: any image_t::PIXEL_FORMAT_* that encode_image supports (BGR,
// RGB, GRAY, BAYER_RGGB like a Point Grey camera, JPEG, PNG).
stereo_image_t make_stereo_message(const SimFrame& frame, int64_t utime, int64_t seq, int32_t pixelformat);
depth_image_t make_depth_message(const SimFrame& frame, const RigCalibration& rig, int64_t utime, int64_t seq);
// Surface and phenomena images as PNG (png = false: raw GRAY).
sim_ground_truth_t make_truth_message(const SimFrame& frame, const Scene& scene, const Pose2D& pose, int64_t utime,
                                      int64_t seq, bool png = true);

}  // namespace ivoa::sim
