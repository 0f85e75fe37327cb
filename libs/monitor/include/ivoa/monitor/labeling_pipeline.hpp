#pragma once
// Pair -> monitor -> label, in one object: what the depth_monitor process
// does live and what the dataset tool does offline on a log, so the two
// paths produce the same labels by construction.
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/query_grid.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/monitor/depth_monitor.hpp"
#include "ivoa/monitor/frame_pairer.hpp"

namespace ivoa::monitor {

struct LabeledFrame {
  obstacle_grid_t depth_grid;     // the monitor's verdicts for the stereo frame's cells
  introspection_labels_t labels;  // Algorithm 1
  double monitor_ms = 0;          // time the depth verdict took
};

struct PipelineOutcome {
  int64_t stereo_utime = 0;
  obstacle_grid_t stereo_grid;
  std::optional<LabeledFrame> labeled;      // empty: no depth frame within the pairing tolerance
  std::optional<int64_t> nearest_depth_us;  // unlabeled: the nearest depth frame held, depth - stereo utime
};

class LabelingPipeline {
 public:
  LabelingPipeline(const RigCalibration& rig, const QueryGridConfig& grid_config,
                   const DepthMonitorConfig& monitor_config = {}, const PairingConfig& pairing = {});

  // Each returns the stereo frames whose pairing became final.
  // add_depth throws ImageError for a depth image that does not fit the
  // calibration; add_stereo throws LabelError for a grid of other geometry.
  std::vector<PipelineOutcome> add_depth(int64_t utime, cv::Mat depth_mm);
  std::vector<PipelineOutcome> add_stereo(obstacle_grid_t stereo_grid);
  std::vector<PipelineOutcome> flush();

  const QueryGrid& grid() const { return grid_; }
  const RigCalibration& rig() const { return rig_; }
  const PairingCounters& counters() const { return pairer_.counters(); }
  const std::string& last_clock_event() const { return pairer_.last_clock_event(); }

 private:
  std::vector<PipelineOutcome> finish(std::vector<FramePairer<cv::Mat, obstacle_grid_t>::Result> results);

  RigCalibration rig_;
  QueryGrid grid_;
  DepthMonitor monitor_;
  FramePairer<cv::Mat, obstacle_grid_t> pairer_;
};

}  // namespace ivoa::monitor
