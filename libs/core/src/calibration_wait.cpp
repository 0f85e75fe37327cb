#include "ivoa/core/calibration_wait.hpp"

#include <utility>

#include <spdlog/spdlog.h>

#include "ivoa/core/heartbeat.hpp"

namespace ivoa {

CalibrationWait::CalibrationWait(Heartbeat& heartbeat, std::string calibration_channel)
    : heartbeat_(heartbeat), channel_(std::move(calibration_channel)) {
  heartbeat_.set_counter(kFramesWithoutCalibration, 0);
}

void CalibrationWait::skip(const std::string& what, const std::string& reason) {
  heartbeat_.add_to_counter(kFramesWithoutCalibration, 1);
  if (std::exchange(warned_, true)) return;
  spdlog::warn("skipping {}: no calibration yet on {}{} (such inputs are counted as {})", what, channel_, reason,
               kFramesWithoutCalibration);
}

}  // namespace ivoa
