#pragma once
// Writes a short simulated session straight into an LCM log (in process,
// through the file:// transport), the way the simulator driver and logger
// would record it: calibration, stereo pairs, depth images a few ms later,
// and ground truth.
#include <functional>
#include <string>
#include <vector>

#include "ivoa/sim/simulator.hpp"

namespace ivoa {
class Bus;
}

namespace ivoa::test {

struct SimLogFrame {
  int64_t utime = 0;
  int64_t depth_utime = 0;
  sim::Pose2D pose;
  uint64_t index = 0;
};

struct SimLog {
  std::vector<SimLogFrame> frames;
  RigCalibration rig;
};

// `extra` is called after each frame is written, with the bus, to add
// messages (e.g. recorded labels).
SimLog write_sim_log(const std::string& path, const std::string& scene_file, uint64_t seed, int frames,
                     const std::function<void(Bus&, const SimLogFrame&, const sim::SimFrame&)>& extra = {});

}  // namespace ivoa::test
