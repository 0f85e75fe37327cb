#pragma once
// Turns LCM logs into a dataset session. Labels either come from the log
// (the INTROSPECTION_LABELS the live processes recorded) or are made again
// offline by re-running a stereo detector and the depth monitor on the
// log's raw images, so one raw log trains introspection for any perception
// model. Both paths share the monitor's LabelingPipeline with the live
// process.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ivoa/core/channels.hpp"
#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/monitor/labeling_pipeline.hpp"
#include "ivoa/stereo/config.hpp"

namespace ivoa::dataset {

inline constexpr const char* kRecordedLabels = "recorded";

struct BuildOptions {
  // "recorded" (use the log's labels), or a detector to re-run ("jppc", "dense").
  std::string labels = kRecordedLabels;
  stereo::DetectorConfig detector;
  QueryGridConfig grid;  // for re-run labels; recorded labels carry their own
  // Recorded labels: > 0 cuts patches of this side (pixels) around each
  // recorded cell instead of the recording grid's; cells whose patch would
  // leave the image are skipped. Re-run labels use grid.patch_size.
  int recorded_patch_size = 0;
  // > 0: footprint-scaled patches (SessionInfo::patch_scale), for either
  // kind of labels; 0: fixed squares.
  double patch_scale = 0;
  // (0, 1]: store this fraction of the TN cells (SessionInfo::tn_kept),
  // chosen by frame time and cell, so a rebuild keeps the same ones. TN is
  // about two thirds of the cells and training draws the classes evenly, so
  // 0.25 saves about 45 % of the disk (the full run's seeds 13-14: 4.8 -> 2.7 GB).
  // Per-class accuracy on such a session is unbiased; overall accuracy and
  // failure precision are not, so keep 1 for test sessions.
  double keep_tn = 1;
  monitor::DepthMonitorConfig monitor;
  monitor::PairingConfig pairing;
  std::string environment;  // "" = the simulator's truth messages, else the scene name (indoor_*/outdoor_*)
  int views = 1;            // 2: store the ground-warped right view under each patch (SessionInfo::views)
  // Store each sample's stereo::Evidence (SessionInfo::evidence_size), from
  // the labels' detector re-run on the frame with `detector` settings (for
  // recorded labels those must be the settings the log was recorded with:
  // samples where the re-run verdict differs get NaN evidence and are
  // counted). Detectors without evidence (dense) store none.
  bool evidence = true;
  std::string stereo_channel{channels::kStereoImages};
  std::string depth_channel{channels::kDepthImage};
  std::string calibration_channel{channels::kRigCalibration};
  std::string labels_channel{channels::kIntrospectionLabels};
  std::string truth_channel{channels::kSimGroundTruth};
};

struct BuildReport {
  int64_t events = 0;
  int64_t stereo_frames = 0;
  int64_t frames_labelled = 0;   // frames that gave samples
  int64_t frames_unmatched = 0;  // no depth frame within the pairing tolerance
  int64_t samples = 0;
  int64_t tn_dropped = 0;             // TN cells left out (keep_tn < 1)
  int64_t patches_outside = 0;        // labelled cells skipped: their patch leaves the image
  int64_t frames_repeated = 0;        // labels of a frame already stored (a log given twice): skipped
  int64_t bad_messages = 0;           // undecodable or inconsistent, skipped
  int64_t evidence_mismatches = 0;    // samples whose re-run verdict differs from the label's (NaN evidence)
  cv::Size image_size;                // the session's: its first stored frame's (no frame stored: its first frame's)
  int64_t frames_other_size = 0;      // stereo frames of another size (not the model's to know), stored or not
  std::vector<std::string> problems;  // log damage (with byte offsets) and bad messages
  std::array<int64_t, kNumClasses> class_counts{};
};

// Says so when most stereo frames found no depth frame within the pairing
// tolerance (a depth camera slower than the stereo one, or on another
// clock), naming the flag that widens it; "" otherwise.
std::string pairing_warning(const BuildReport& report, const monitor::PairingConfig& pairing);

// Called with (bytes done, bytes total) while reading.
using ProgressCallback = std::function<void(uint64_t, uint64_t)>;

class SessionBuilder {
 public:
  // Throws DatasetError / std::invalid_argument for a bad option.
  SessionBuilder(const std::string& dataset_root, const std::string& session, BuildOptions options);
  ~SessionBuilder();

  // Reads one log (call again for the next file of a split session). A
  // damaged log yields everything before the damage, and the problem
  // (byte offset) goes to the report. Throws DatasetError for a log that
  // cannot be opened or holds no RIG_CALIBRATION.
  void add_log(const std::string& path, const ProgressCallback& progress = {});
  // Writes the session. Throws DatasetError, writing nothing, if its logs
  // hold nothing to label from (no labels recorded, or no depth to re-label).
  BuildReport finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ivoa::dataset
