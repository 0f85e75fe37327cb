#pragma once
// The driver's main loop: takes frames from the two camera threads, pairs
// them by timestamp, publishes STEREO_IMAGES, RIG_CALIBRATION (>= 1 Hz) and
// the heartbeat, fires software triggers, and gives up with a clear error
// if the cameras never appear. Only this thread publishes.
#include <memory>
#include <string>

#include "ivoa/aravis_stereo/camera_worker.hpp"
#include "ivoa/aravis_stereo/clock_mapper.hpp"
#include "ivoa/aravis_stereo/stereo_message.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/channels.hpp"

namespace ivoa {
class Bus;
class Heartbeat;
}  // namespace ivoa

namespace ivoa::aravis_stereo {

struct StereoDriverOptions {
  OutputFormat output = OutputFormat::kRaw;
  double pair_tolerance_ms = 0;                // max left/right time difference of a pair; 0 = half the frame period
  PairingClock clock = PairingClock::kMapped;  // also the published utime, except kDevice (host receive time)
  double frame_rate_hz = 30;                   // camera rate (sets the default tolerance and the software-trigger rate)
  bool software_trigger = false;               // fire both cameras from this loop at frame_rate_hz
  WorkerOptions worker;                        // frame timeout and reconnect back-off
  double startup_timeout_s = 15;               // exit if a camera has not opened by then; 0 = wait forever
  std::string stereo_channel = std::string(channels::kStereoImages);
  std::string rig_channel = std::string(channels::kRigCalibration);
  double rig_rate_hz = 1.0;  // RIG_CALIBRATION publications per second
  std::string source_name = "aravis";
  std::string rig_path;  // for log lines
};

class StereoDriver {
 public:
  StereoDriver(Bus& bus, Heartbeat& heartbeat, RigCalibration rig, const StereoDriverOptions& options,
               std::unique_ptr<CameraSource> left, std::unique_ptr<CameraSource> right);
  ~StereoDriver();

  // Runs until SIGINT/SIGTERM (exit code 0), a camera that cannot be
  // configured (2) or cameras that never open (1).
  int run();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace ivoa::aravis_stereo
