#pragma once
// The depth_monitor process's logic, separate from main() so tests can run
// it in-process on memq://: subscribes to DEPTH_IMAGE, OBSTACLES_STEREO and
// RIG_CALIBRATION, publishes OBSTACLES_DEPTH and INTROSPECTION_LABELS.
#include <memory>
#include <string>
#include <vector>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration_wait.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/seq_gaps.hpp"
#include "ivoa/monitor/labeling_pipeline.hpp"

namespace ivoa {

struct MonitorNodeOptions {
  std::string depth_channel{channels::kDepthImage};
  std::string stereo_channel{channels::kObstaclesStereo};
  std::string calibration_channel{channels::kRigCalibration};
  std::string depth_out_channel{channels::kObstaclesDepth};
  std::string labels_out_channel{channels::kIntrospectionLabels};
  QueryGridConfig grid;
  monitor::DepthMonitorConfig monitor;
  monitor::PairingConfig pairing;
};

class MonitorNode {
 public:
  MonitorNode(Bus& bus, Heartbeat& heartbeat, MonitorNodeOptions options);
  // A calibration to start with (--calibration FILE), as if it had come on
  // the channel; a different one received later replaces it. Throws what
  // building the monitor for it throws.
  void set_calibration(const RigCalibration& rig);
  // Decides what is still pending (on shutdown, or at the end of a log).
  void flush();

 private:
  void on_calibration(const rig_calibration_t& msg);
  void use_calibration(const RigCalibration& rig);  // builds the monitor for it; throws
  void on_depth(const depth_image_t& msg);
  void on_stereo(const obstacle_grid_t& msg);
  // False (counted, warned about once) while no calibration has arrived.
  bool has_calibration(const std::string& where);
  // Counts (and warns once of) depth frames whose own intrinsics are not the
  // calibration's: labelled with the calibration's, as always.
  void note_other_intrinsics(const depth_image_t& msg, const std::string& where);
  // kFlushed: frames decided because nothing more will come (a stop, a new
  // calibration) say nothing about how the streams pair.
  enum class Pairing { kLive, kFlushed };
  void publish(std::vector<monitor::PipelineOutcome> outcomes, Pairing pairing = Pairing::kLive);
  // A run of unpaired stereo frames long enough to mean the streams do not
  // pair is said (state, a rate-limited warning with the nearest depth
  // frame's distance); a pair ends it.
  void note_unpaired(const monitor::PipelineOutcome& outcome);
  void note_paired();
  monitor::PairingCounters run_counters() const;  // of every pipeline of this run
  void update_counters();
  void report_clock_events(const monitor::ClockCounters& now, monitor::ClockCounters& seen, const std::string& channel);

  Bus& bus_;
  Heartbeat& heartbeat_;
  MonitorNodeOptions options_;
  CalibrationWait calibration_wait_;
  SeqGaps missed_;                   // of the depth frames
  CalibrationChanges calibrations_;  // to tell a new one from the same one again
  std::unique_ptr<monitor::LabelingPipeline> pipeline_;
  int64_t labelled_cells_ = 0;
  bool warned_other_intrinsics_ = false;
  struct UnpairedRun {
    int64_t frames = 0, first_utime = 0;
    bool said = false;  // the state says "unpaired"
  } unpaired_run_;
  double last_unpaired_warning_ms_ = -1e18;
  monitor::ClockCounters depth_clock_seen_, stereo_clock_seen_;  // what update_counters last reported
  monitor::PairingCounters earlier_pipelines_;                   // of the pipelines a calibration change replaced
};

}  // namespace ivoa
