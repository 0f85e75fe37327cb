#pragma once
// The stereo detector process's logic, separate from main() so tests can run
// it in-process on memq://: STEREO_IMAGES + RIG_CALIBRATION in, one
// obstacle_grid_t per processed frame out on OBSTACLES_STEREO.
//
// The LCM thread only queues: the newest stereo frame goes into a latest-value
// mailbox (a frame pushed out before the worker took it counts as dropped;
// StereoDetectorOptions::queue_frames says how many it holds) and
// calibrations are kept under a lock. A worker thread decodes the frame it
// takes (the newest, or with a queue the oldest held), (re)builds the
// detector and query grid when the calibration changed, evaluates the grid
// and publishes it. Bad input (undecodable or wrongly sized
// images, invalid calibrations) is reported to the heartbeat, counted and
// skipped; frames before any calibration are counted and skipped.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration_wait.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/mailbox.hpp"
#include "ivoa/core/query_grid.hpp"
#include "ivoa/core/seq_gaps.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa {

struct StereoDetectorOptions {
  std::string model = "jppc";  // "jppc" or "dense"
  stereo::DetectorConfig detector;
  QueryGridConfig grid;
  std::string stereo_channel{channels::kStereoImages};
  std::string calibration_channel{channels::kRigCalibration};
  std::string output_channel{channels::kObstaclesStereo};
  int64_t max_frames = 0;  // finish after publishing this many grids; 0 = never
  // Frames held while the worker is busy. 1 (live): only the newest, older
  // ones count as dropped. More: that many, oldest first, so a recording of
  // a simulator that renders ahead loses no frame to a stall at start-up.
  int queue_frames = 1;
  // Reading a log (already said at start): failed publishes are only counted.
  bool publish_failures_expected = false;
};

class StereoDetectorNode {
 public:
  // Heartbeat counters it keeps besides in/out/dropped/bad input.
  static constexpr const char* kFramesWithoutCalibration = ivoa::kFramesWithoutCalibration;
  static constexpr const char* kCalibrationsApplied = "calibrations_applied";

  StereoDetectorNode(Bus& bus, Heartbeat& heartbeat, StereoDetectorOptions options);
  ~StereoDetectorNode();
  StereoDetectorNode(const StereoDetectorNode&) = delete;
  StereoDetectorNode& operator=(const StereoDetectorNode&) = delete;

  // A calibration to start with (e.g. from a file); RIG_CALIBRATION
  // messages still replace it.
  void set_calibration(const RigCalibration& rig);

  // Subscribes and starts the worker. stop() lets it finish the frames
  // queued, then joins it (also at destruction).
  void start();
  void stop();

  bool finished() const { return finished_; }  // max_frames published
  int64_t published() const { return published_; }

 private:
  struct Frame {
    stereo_image_t msg;
    double received_ms = 0;
  };
  void on_stereo(const stereo_image_t& msg);
  void on_calibration(const rig_calibration_t& msg);
  void run_worker();
  void process(const Frame& frame);
  bool update_detector();  // false while no calibration has arrived

  Bus& bus_;
  Heartbeat& heartbeat_;
  StereoDetectorOptions options_;
  LatestMailbox<Frame> mailbox_;
  SeqGaps missed_;  // LCM thread only

  std::mutex calibration_mutex_;
  std::optional<RigCalibration> calibration_;  // newest valid calibration
  CalibrationChanges calibrations_;            // to tell a new one from the same one again
  uint64_t calibration_version_ = 0;

  // Worker-thread state.
  uint64_t detector_version_ = 0;
  std::unique_ptr<stereo::ObstacleDetector> detector_;
  std::unique_ptr<QueryGrid> grid_;
  CalibrationWait calibration_wait_;

  std::atomic<bool> finished_{false};
  std::atomic<int64_t> published_{0};
  std::thread worker_;
};

}  // namespace ivoa
