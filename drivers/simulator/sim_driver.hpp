#pragma once
// The simulator driver's loop: drives the robot along its trajectory and,
// per frame, publishes the stereo pair, the depth image and the ground truth,
// plus the rig calibration at start and at least once per second of session
// time. Message times are start_utime + frame / rate, so a session (scene,
// seed, rate, start time) is reproducible bit for bit.
#include <cstdint>
#include <memory>
#include <string>

#include "ivoa/core/channels.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"

namespace lcm {
class LogFile;
}

namespace ivoa {
class Bus;
class Heartbeat;
}  // namespace ivoa

namespace ivoa::sim {

struct SimDriverConfig {
  std::string scene_file;             // YAML scene
  uint64_t seed = 1;                  // scene and trajectory seed: one session
  double rate_hz = 10.0;              // frames per second of session time
  bool realtime = true;               // pace frames by the wall clock (skip frames when rendering falls behind)
  int64_t frames = 0;                 // stop after this many frames (0: no limit)
  double duration_s = 0;              // stop after this much session time (0: no limit)
  int64_t start_utime = -1;           // utime of frame 0 (< 0: now)
  int32_t pixelformat = 0;            // image_t::PIXEL_FORMAT_* of the published pair (0: BAYER_RGGB)
  double depth_offset_ms = 4.0;       // depth image utime = stereo utime + this (its own clock)
  double calibration_period_s = 1.0;  // RIG_CALIBRATION period in session time
  bool publish_truth = true;
  std::string log_file;  // also write every message to this LCM log, timestamped by utime
  std::string stereo_channel{channels::kStereoImages};
  std::string depth_channel{channels::kDepthImage};
  std::string rig_channel{channels::kRigCalibration};
  std::string truth_channel{channels::kSimGroundTruth};
};

class SimDriver {
 public:
  // Throws SceneSpecError (bad scene file) or std::runtime_error (log file).
  SimDriver(SimDriverConfig config, SimulatorConfig simulator_config, Bus& bus, Heartbeat* heartbeat);
  ~SimDriver();

  // Publishes frames until the frame count or duration is reached or a stop
  // is requested. Returns the number of frames published. Throws
  // std::runtime_error when the --log cannot be written (disk full).
  int64_t run();
  // Renders and publishes frame `index` (session time index / rate).
  void publish_frame(int64_t index);
  // Messages LCM refused (a channel name it does not take, a file:// output
  // it cannot write): not published, counted and said at the end.
  int64_t publish_failures() const { return publish_failures_; }
  const Simulator& simulator() const { return simulator_; }
  int64_t start_utime() const { return start_utime_; }

 private:
  int64_t frame_utime(int64_t index) const;
  void publish_calibration(int64_t utime);
  template <class Msg>
  void send(const std::string& channel, Msg& msg, int64_t utime);

  SimDriverConfig config_;
  Scene scene_;
  Simulator simulator_;
  Trajectory trajectory_;
  Bus& bus_;
  Heartbeat* heartbeat_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t start_utime_ = 0;
  int64_t seq_ = 0;
  int64_t last_calibration_utime_ = 0;
  int64_t publish_failures_ = 0;
};

}  // namespace ivoa::sim
