#pragma once
// The introspection process's logic: newest left image in, heatmaps and
// per-query-cell predictions out. A receive handler drops each stereo frame
// into a latest-value mailbox; a worker thread runs the CNN on the newest
// one, so a slow CPU skips frames (counted) instead of falling behind
// (IntrospectionNodeOptions::queue_frames holds more, oldest first).
// The query cells' predictions are also given the detector's verdict of the
// same frame, from its obstacle grid; the CNN is slower than the detector,
// so that grid is normally in by the time the CNN is done, and the worker
// waits a bounded time for it otherwise (then the verdict is unknown, counted).
// A grid from another detector than the model was trained for gives the
// query cells' geometry but no verdicts (counted, warned about once): the
// model knows when its own detector errs, not another's.
// Frames of an image size the model was not trained on (ModelInfo::
// image_sizes) are run all the same, since patches are cut on the ground
// and resized, but counted (frames_untrained_size) and warned about once
// per size: its accuracy on that camera is unmeasured.
// A two-view model also needs the rig calibration, to warp the right image
// onto the ground plane; frames before the first calibration are skipped
// (counted apart, as frames_without_calibration: CalibrationWait).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/calibration_wait.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "ivoa/core/seq_gaps.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/mailbox.hpp"
#include "ivoa/introspection/model.hpp"
#include "ivoa/introspection_t.hpp"

namespace ivoa {

struct IntrospectionNodeOptions {
  std::string stereo_channel{channels::kStereoImages};
  std::string grid_channel{channels::kObstaclesStereo};  // "" = no query cells
  std::string out_channel{channels::kIntrospection};
  std::string calibration_channel{channels::kRigCalibration};  // two-view models only
  // A two-view model's calibration to start with (--calibration FILE), so
  // that the first frames need not wait for the channel's; a calibration
  // received later replaces it.
  std::optional<RigCalibration> initial_calibration;
  std::string initial_calibration_file;  // where it was read, for messages
  // After the CNN, how long to wait for the detector's grid of the frame
  // (its verdicts); the query cells' geometry comes from any recent grid.
  std::chrono::milliseconds grid_wait{200};
  // Before the first frame, run the model once on a blank frame of this
  // size (the camera's) on the worker thread; the constructor returns after.
  // default_warm_up_size() is the size the model was trained on.
  std::optional<cv::Size> warm_up;
  // Frames held while the CNN is busy: 1 keeps only the newest (live); more
  // keeps that many, oldest first (a log read with ?speed=0, a burst).
  int queue_frames = 1;
};

// The detector's most recent obstacle grids, by utime (thread-safe).
class RecentGrids {
 public:
  // Keeps the newest `kept` grids: at least the frames queued for the CNN
  // and a second more, so a queued frame still finds its own grid.
  explicit RecentGrids(size_t kept = 16) : kept_(kept) {}
  void put(const obstacle_grid_t& grid);
  std::optional<obstacle_grid_t> latest() const;
  // The grid of the frame `utime`, waiting up to `wait` for it to arrive
  // (not at all once closed).
  std::optional<obstacle_grid_t> of_frame(int64_t utime, std::chrono::milliseconds wait);
  // No grid arrives any more (LCM is no longer handled): ends every wait.
  void close();

 private:
  const size_t kept_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<obstacle_grid_t> grids_;  // oldest first
  bool closed_ = false;
};

// The predictions at the grid's in-image cells, in cell order: looked up in
// the heatmaps, except that a footprint-scaled model (ModelInfo::patch_scale)
// predicts each cell whose square is larger than the patch (the rows near
// the robot) from its own square of `input` (the model's input image).
std::vector<introspection::Prediction> query_predictions(introspection::IntrospectionModel& model,
                                                         const introspection::Heatmaps& heatmaps, const cv::Mat& input,
                                                         const obstacle_grid_t& query_grid);

// Builds the message for one frame (exposed for tests); `predictions` are
// query_predictions() of `query_grid`. With `grid_is_this_frames`, its
// states are the detector's verdicts for this frame and the predictions are
// also given those verdicts; otherwise the verdicts are unknown.
introspection_t make_introspection_message(const introspection::IntrospectionModel& model,
                                           const introspection::Heatmaps& heatmaps, int64_t utime, int image_width,
                                           int image_height, const obstacle_grid_t* query_grid,
                                           const std::vector<introspection::Prediction>& predictions, int mc_passes,
                                           bool grid_is_this_frames);

// Runs the model once on a blank frame of `image_size` (views stacked as
// for a real one), with `near_cells` squares of their own for a
// footprint-scaled model, so LibTorch's one-time set-up is paid before the
// first real frame instead of delaying it. Call it on the thread that will
// run the model: the set-up is partly per thread. Returns how long it took, ms.
double warm_up(introspection::IntrospectionModel& model, cv::Size image_size, int near_cells = 40);
// The first image size the model was trained on, or the simulator's 960x600
// for a model that does not say.
cv::Size default_warm_up_size(const introspection::ModelInfo& info);

class IntrospectionNode {
 public:
  IntrospectionNode(Bus& bus, Heartbeat& heartbeat, std::unique_ptr<introspection::IntrospectionModel> model,
                    IntrospectionNodeOptions options, int mc_passes);
  ~IntrospectionNode();  // stops the worker
  // Lets the frame in hand and those waiting (one, or --queue-frames)
  // finish, then stops the worker (before the final heartbeat, so it counts
  // them). Idempotent.
  void stop();

  int64_t frames_done() const { return frames_done_.load(); }

 private:
  struct Frame {
    stereo_image_t msg;
    double received_ms;
  };
  void warm_up_worker();
  void work();
  void process(const Frame& frame);
  void on_calibration(const rig_calibration_t& msg);
  void on_grid(obstacle_grid_t grid);
  // The image the model runs on (left, or left over the ground-warped
  // right); empty after reporting bad input.
  cv::Mat model_input(const Frame& frame, const std::string& where, cv::Mat& left);
  // Builds the ground warp of a calibration received since (worker thread only).
  void update_warp();
  // Counts a frame of a size the model was not trained on, warning once per size.
  void check_image_size(cv::Size size);

  Bus& bus_;
  Heartbeat& heartbeat_;
  std::unique_ptr<introspection::IntrospectionModel> model_;
  IntrospectionNodeOptions options_;
  int mc_passes_;
  LatestMailbox<Frame> frames_;
  RecentGrids grids_;
  bool warned_other_detector_ = false;               // LCM thread only
  std::vector<cv::Size> warned_sizes_;               // untrained ones (worker thread only)
  SeqGaps missed_;                                   // LCM thread only
  std::optional<CalibrationWait> calibration_wait_;  // two-view models; worker thread only
  std::mutex calibration_mutex_;
  CalibrationChanges calibrations_;        // to tell a new one from the same one again
  std::optional<RigCalibration> new_rig_;  // handed to the worker, which builds the warp
  std::string new_rig_source_;             // where it came from, for an error
  std::unique_ptr<GroundWarp> warp_;       // worker thread only
  std::atomic<int64_t> frames_done_{0};
  std::thread worker_;
};

}  // namespace ivoa
