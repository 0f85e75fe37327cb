#include "stereo_detector_node.hpp"

#include <algorithm>
#include <chrono>

#include <spdlog/spdlog.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/time.hpp"

namespace ivoa {
namespace {

std::string frame_name(const std::string& channel, const stereo_image_t& msg) {
  return channel + " seq " + std::to_string(msg.seq) + " (utime " + std::to_string(msg.utime) + ")";
}

// decode_image, its error saying which camera's image it was.
cv::Mat decode_side(const image_t& image, const char* side) {
  try {
    return decode_image(image);
  } catch (const std::exception& e) {
    throw ImageError(std::string(side) + " image: " + e.what());
  }
}

}  // namespace

StereoDetectorNode::StereoDetectorNode(Bus& bus, Heartbeat& heartbeat, StereoDetectorOptions options)
    : bus_(bus),
      heartbeat_(heartbeat),
      options_(std::move(options)),
      mailbox_(static_cast<size_t>(std::max(options_.queue_frames, 1))),
      calibration_wait_(heartbeat_, options_.calibration_channel) {
  heartbeat_.set_counter(kCalibrationsApplied, 0);
  heartbeat_.set_counter(kFramesMissed, 0);
}

StereoDetectorNode::~StereoDetectorNode() { stop(); }

void StereoDetectorNode::set_calibration(const RigCalibration& rig) {
  std::lock_guard<std::mutex> lock(calibration_mutex_);
  calibration_ = rig;
  calibrations_.take(rig);
  ++calibration_version_;
}

void StereoDetectorNode::start() {
  bus_.subscribe<stereo_image_t>(options_.stereo_channel,
                                 [this](const stereo_image_t& msg, const ReceiveInfo&) { on_stereo(msg); });
  bus_.subscribe<rig_calibration_t>(options_.calibration_channel,
                                    [this](const rig_calibration_t& msg, const ReceiveInfo&) { on_calibration(msg); });
  heartbeat_.set_state("waiting for calibration");
  worker_ = std::thread([this] { run_worker(); });
}

void StereoDetectorNode::stop() {
  mailbox_.close();
  if (worker_.joinable()) worker_.join();
}

void StereoDetectorNode::on_stereo(const stereo_image_t& msg) {
  heartbeat_.count_in();
  heartbeat_.add_to_counter(kFramesMissed, missed_.add(msg.seq));
  const uint64_t dropped_before = mailbox_.dropped();
  mailbox_.put(Frame{msg, monotonic_ms()});
  if (mailbox_.dropped() != dropped_before) heartbeat_.count_dropped();
}

void StereoDetectorNode::on_calibration(const rig_calibration_t& msg) {
  std::lock_guard<std::mutex> lock(calibration_mutex_);
  try {
    std::optional<RigCalibration> rig = calibrations_.take_if_new(msg);
    if (!rig) return;
    calibration_ = std::move(rig);
  } catch (const CalibrationError& e) {
    heartbeat_.bad_input(std::string("ignoring calibration: ") + e.what());
    return;
  }
  ++calibration_version_;
}

// A calibration the detector cannot be built for (OpenCV cannot rectify
// it, or its maps do not fit in memory) is bad input, and the detector
// built before keeps running: as for a calibration that fails validation.
bool StereoDetectorNode::update_detector() {
  std::optional<RigCalibration> rig;
  {
    std::lock_guard<std::mutex> lock(calibration_mutex_);
    if (calibration_version_ == detector_version_) return detector_ != nullptr;
    rig = calibration_;
    detector_version_ = calibration_version_;
  }
  if (!rig) return false;
  try {
    auto detector = stereo::make_detector(options_.model, *rig, options_.detector);
    auto grid = std::make_unique<QueryGrid>(options_.grid, CameraModel(rig->left, rig->left_to_robot));
    detector_ = std::move(detector);
    grid_ = std::move(grid);
  } catch (const std::exception& e) {
    heartbeat_.bad_input(std::string("cannot use calibration '") + rig->rig_name + "': " + e.what() +
                         (detector_ ? " (the one before stays)" : ""));
    return detector_ != nullptr;
  }
  heartbeat_.add_to_counter(kCalibrationsApplied, 1);
  heartbeat_.set_state("running");
  spdlog::info("{} detector ready for rig '{}' ({}x{}), {} grid cells ({} with the patch in view)", options_.model,
               rig->rig_name, rig->left.width, rig->left.height, grid_->size(), grid_->count_in_image());
  return true;
}

// After stop() the frames still queued are processed (take() no longer
// waits), so a stop at the end of a recording labels its last frames; past
// --max-frames they are counted as dropped. None is left unaccounted for.
void StereoDetectorNode::run_worker() {
  while (true) {
    const std::optional<Frame> frame = mailbox_.take(std::chrono::milliseconds(100));
    if (!frame) {
      if (mailbox_.closed()) return;
    } else if (finished_) {
      heartbeat_.count_dropped();
    } else {
      process(*frame);
    }
  }
}

void StereoDetectorNode::process(const Frame& frame) {
  const std::string name = frame_name(options_.stereo_channel, frame.msg);
  if (!update_detector()) {
    calibration_wait_.skip(name);
    return;
  }
  calibration_wait_.end();
  if (const std::string why = stereo_times_error(frame.msg); !why.empty()) {
    heartbeat_.bad_input(name + ": " + why);
    return;
  }
  const double start_ms = monotonic_ms();
  obstacle_grid_t out = make_obstacle_grid(*grid_, detector_->name(), frame.msg.utime);
  try {
    // Colour, as the offline dataset tool passes it. The detectors convert to
    // gray first themselves, so gray input would give the same verdicts
    // (test: Detectors.GrayAndColourInputGiveTheSameVerdicts).
    const cv::Mat left = decode_side(frame.msg.left, "left");
    const cv::Mat right = decode_side(frame.msg.right, "right");
    detector_->set_frame(left, right);
    detector_->evaluate(*grid_, out);
  } catch (const std::exception& e) {  // ImageError, stereo::FrameError, or OpenCV's on a frame it cannot take
    heartbeat_.bad_input(name + ": " + e.what());
    return;
  }
  out.compute_ms = monotonic_ms() - start_ms;
  if (!bus_.publish(options_.output_channel, out)) {
    if (!heartbeat_.counter("publish_failures") && !options_.publish_failures_expected)
      spdlog::error("publishing on {} failed (counted as publish_failures from now on)", options_.output_channel);
    heartbeat_.add_to_counter("publish_failures", 1);  // not counted as out
    return;
  }
  heartbeat_.count_out();
  heartbeat_.latency(monotonic_ms() - frame.received_ms);
  const int64_t published = ++published_;
  if (options_.max_frames > 0 && published >= options_.max_frames) finished_ = true;
}

}  // namespace ivoa
