#pragma once
// The inputs a process skips while it has no rig calibration to use: a
// consumer started a moment before the driver sees a frame or two first.
// Not bad input: they are counted apart, and warned about once per wait.
#include <string>

namespace ivoa {
class Heartbeat;

class CalibrationWait {
 public:
  // Sets the heartbeat's kFramesWithoutCalibration counter to 0.
  CalibrationWait(Heartbeat& heartbeat, std::string calibration_channel);

  // Counts `what` (e.g. "STEREO_IMAGES #12") as skipped; the first of a wait
  // is also a warning, with `reason` (", which ... needs") if given.
  void skip(const std::string& what, const std::string& reason = "");
  // A calibration is in use: the wait is over, and a later one warns again.
  void end() { warned_ = false; }

 private:
  Heartbeat& heartbeat_;
  std::string channel_;
  bool warned_ = false;
};

}  // namespace ivoa
