#include "monitor_node.hpp"

#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/monitor/labeler.hpp"

namespace ivoa {

// Heartbeat counter of depth frames whose intrinsics are not the calibration's.
constexpr const char* kDepthIntrinsicsDiffer = "depth_intrinsics_differ";
namespace {

// Stereo frames without a depth partner for this long (stream time), and at
// least this many, before it is said: a depth camera slower than the stereo
// one pairs some frames every period, so only a stream that pairs none (or
// a depth stream gone) is meant. Stream time: a log replayed fast says the same.
constexpr int64_t kUnpairedSpanToSayUs = 2'000'000;
constexpr int64_t kUnpairedRunToSay = 5;
constexpr double kUnpairedWarningIntervalMs = 10'000;
constexpr const char* kUnpairedState = "unpaired: no depth frame near the stereo frames";

}  // namespace

MonitorNode::MonitorNode(Bus& bus, Heartbeat& heartbeat, MonitorNodeOptions options)
    : bus_(bus),
      heartbeat_(heartbeat),
      options_(std::move(options)),
      calibration_wait_(heartbeat_, options_.calibration_channel) {
  bus_.on_decode_error([this](const std::string& what) { heartbeat_.bad_input(what); });
  bus_.subscribe<rig_calibration_t>(options_.calibration_channel,
                                    [this](const rig_calibration_t& m, const ReceiveInfo&) { on_calibration(m); });
  bus_.subscribe<depth_image_t>(options_.depth_channel,
                                [this](const depth_image_t& m, const ReceiveInfo&) { on_depth(m); });
  bus_.subscribe<obstacle_grid_t>(options_.stereo_channel,
                                  [this](const obstacle_grid_t& m, const ReceiveInfo&) { on_stereo(m); });
  heartbeat_.set_counter(kFramesMissed, 0);
  heartbeat_.set_counter(kDepthIntrinsicsDiffer, 0);
  heartbeat_.set_state("waiting for calibration");
}

bool MonitorNode::has_calibration(const std::string& where) {
  if (pipeline_) return true;
  calibration_wait_.skip(where);
  return false;
}

void MonitorNode::set_calibration(const RigCalibration& rig) {
  use_calibration(rig);
  calibrations_.take(rig);  // the same one on the channel is not a change
}

void MonitorNode::on_calibration(const rig_calibration_t& msg) {
  try {
    if (const std::optional<RigCalibration> new_rig = calibrations_.take_if_new(msg)) use_calibration(*new_rig);
  } catch (const std::exception& e) {
    heartbeat_.bad_input(options_.calibration_channel + ": unusable calibration: " + e.what());
  }
}

void MonitorNode::use_calibration(const RigCalibration& rig) {
  // Built first: one that cannot be built leaves the running one as it is.
  auto next = std::make_unique<monitor::LabelingPipeline>(rig, options_.grid, options_.monitor, options_.pairing);
  if (pipeline_) {
    spdlog::info("rig calibration changed: rebuilding the monitor");
    publish(pipeline_->flush(), Pairing::kFlushed);
    earlier_pipelines_ += pipeline_->counters();
  }
  pipeline_ = std::move(next);
  unpaired_run_ = {};
  calibration_wait_.end();
  spdlog::info("calibration '{}': depth {}x{}, {} query cells ({} with a full patch in the left image)", rig.rig_name,
               rig.depth.width, rig.depth.height, pipeline_->grid().size(), pipeline_->grid().count_in_image());
  heartbeat_.set_state("running");
}

void MonitorNode::on_depth(const depth_image_t& msg) {
  heartbeat_.count_in();
  heartbeat_.add_to_counter(kFramesMissed, missed_.add(msg.seq));
  const std::string where = options_.depth_channel + " utime " + std::to_string(msg.utime);
  if (!has_calibration(where)) return;
  if (!(std::isfinite(msg.fx) && std::isfinite(msg.fy) && std::isfinite(msg.cx) && std::isfinite(msg.cy) &&
        msg.fx > 0 && msg.fy > 0)) {
    heartbeat_.bad_input(where + ": intrinsics are not finite and positive");
    return;
  }
  note_other_intrinsics(msg, where);
  try {
    cv::Mat depth = decode_depth(msg);
    if (cv::countNonZero(depth) == 0) {
      heartbeat_.bad_input(where + ": no valid pixel (zero-filled depth image)");
      return;
    }
    publish(pipeline_->add_depth(msg.utime, std::move(depth)));
  } catch (const std::exception& e) {  // ImageError; LabelError of the stereo frame it completes; OpenCV's
    heartbeat_.bad_input(where + ": " + e.what());
  }
}

// A sensor in another mode, or a calibration of another sensor, would
// otherwise be labelled with in silence (fx 100 against 570 went unsaid).
void MonitorNode::note_other_intrinsics(const depth_image_t& msg, const std::string& where) {
  const CameraIntrinsics& cal = pipeline_->rig().depth;
  const auto off = [](double got, double want, double scale) { return std::abs(got - want) > 0.05 * scale; };
  if (!off(msg.fx, cal.K(0, 0), cal.K(0, 0)) && !off(msg.fy, cal.K(1, 1), cal.K(1, 1)) &&
      !off(msg.cx, cal.K(0, 2), cal.width) && !off(msg.cy, cal.K(1, 2), cal.height))
    return;
  heartbeat_.add_to_counter(kDepthIntrinsicsDiffer, 1);
  if (!std::exchange(warned_other_intrinsics_, true))
    spdlog::warn(
        "{}: its intrinsics (fx {:g}, fy {:g}, cx {:g}, cy {:g}) are not the calibration's ({:g}, {:g}, {:g}, "
        "{:g}); labelled with the calibration's (another sensor or mode? recalibrate, or fix the driver's). "
        "Such frames are counted as {}",
        where, msg.fx, msg.fy, msg.cx, msg.cy, cal.K(0, 0), cal.K(1, 1), cal.K(0, 2), cal.K(1, 2),
        kDepthIntrinsicsDiffer);
}

void MonitorNode::on_stereo(const obstacle_grid_t& msg) {
  heartbeat_.count_in();
  const std::string where = options_.stereo_channel + " utime " + std::to_string(msg.utime);
  if (!has_calibration(where)) return;
  try {
    publish(pipeline_->add_stereo(msg));
  } catch (const std::exception& e) {  // LabelError: a grid it cannot label; OpenCV's
    heartbeat_.bad_input(where + ": " + e.what());
  }
}

void MonitorNode::publish(std::vector<monitor::PipelineOutcome> outcomes, Pairing pairing) {
  for (auto& o : outcomes) {
    if (!o.labeled) {  // counted by the pairer
      spdlog::debug("stereo frame {} has no depth frame within the pairing tolerance", o.stereo_utime);
      if (pairing == Pairing::kLive) note_unpaired(o);
      continue;
    }
    if (pairing == Pairing::kLive) note_paired();
    // Only what LCM took counts as out; the rest is counted as refused.
    const int published = int{bus_.publish(options_.depth_out_channel, o.labeled->depth_grid)} +
                          int{bus_.publish(options_.labels_out_channel, o.labeled->labels)};
    heartbeat_.count_out(published);
    if (published < 2) heartbeat_.add_to_counter("publish_failures", 2 - published);
    heartbeat_.latency(o.labeled->monitor_ms);
    for (int8_t l : o.labeled->labels.label) labelled_cells_ += l != introspection_labels_t::LABEL_NONE;
  }
  update_counters();
}

void MonitorNode::note_unpaired(const monitor::PipelineOutcome& o) {
  if (unpaired_run_.frames++ == 0 || o.stereo_utime < unpaired_run_.first_utime)  // or its clock went back
    unpaired_run_.first_utime = o.stereo_utime;
  if (unpaired_run_.frames < kUnpairedRunToSay || o.stereo_utime - unpaired_run_.first_utime < kUnpairedSpanToSayUs)
    return;
  heartbeat_.set_state(kUnpairedState);
  unpaired_run_.said = true;
  const double now = monotonic_ms();
  if (now - last_unpaired_warning_ms_ < kUnpairedWarningIntervalMs) return;
  last_unpaired_warning_ms_ = now;
  const monitor::PairingCounters c = run_counters();
  const std::string nearest = o.nearest_depth_us
                                  ? fmt::format("the nearest {:.1f} ms {} it", std::abs(*o.nearest_depth_us) / 1e3,
                                                *o.nearest_depth_us > 0 ? "after" : "before")
                                  : "no depth frame received";
  spdlog::warn(
      "no stereo frame of the last {:.1f} s ({}) had a depth frame within {:.1f} ms (utime {}: {}); {} of {} "
      "unlabelled so far. Depth on another clock, or at a rate that never falls near the stereo frames? "
      "--sync-tolerance-us half the depth frame period pairs them, with depth up to that much older or newer",
      (o.stereo_utime - unpaired_run_.first_utime) / 1e6, unpaired_run_.frames, options_.pairing.tolerance_us / 1e3,
      o.stereo_utime, nearest, c.unmatched_stereo, c.unmatched_stereo + c.paired);
}

void MonitorNode::note_paired() {
  if (unpaired_run_.said) {
    spdlog::info("stereo frames are paired with depth frames again, after {} unpaired", unpaired_run_.frames);
    heartbeat_.set_state("running");
  }
  unpaired_run_ = {};
}

monitor::PairingCounters MonitorNode::run_counters() const {
  monitor::PairingCounters c = earlier_pipelines_;  // the counts of the whole run
  c += pipeline_->counters();
  return c;
}

void MonitorNode::update_counters() {
  if (!pipeline_) return;
  const monitor::PairingCounters c = run_counters();
  heartbeat_.set_counter("frames_labelled", c.paired);
  heartbeat_.set_counter("stereo_unmatched", c.unmatched_stereo);
  heartbeat_.set_counter("stereo_duplicates", c.duplicate_stereo);
  heartbeat_.set_counter("depth_duplicates", c.duplicate_depth);
  heartbeat_.set_counter("depth_late", c.late_depth);
  heartbeat_.set_counter("depth_dropped", c.dropped_depth);
  heartbeat_.set_counter("cells_labelled", labelled_cells_);
  heartbeat_.set_counter("clock_restarts", c.depth_clock.restarts + c.stereo_clock.restarts);
  report_clock_events(c.depth_clock, depth_clock_seen_, options_.depth_channel);
  report_clock_events(c.stereo_clock, stereo_clock_seen_, options_.stereo_channel);
}

// A frame whose utime jumped alone is bad input; a stream whose clock went
// back and stayed (a log played again) is said once, and followed.
void MonitorNode::report_clock_events(const monitor::ClockCounters& now, monitor::ClockCounters& seen,
                                      const std::string& channel) {
  if (now.outliers > seen.outliers) heartbeat_.bad_input(channel + ": " + pipeline_->last_clock_event());
  if (now.restarts > seen.restarts) spdlog::warn("{}: {}", channel, pipeline_->last_clock_event());
  seen = now;
}

void MonitorNode::flush() {
  if (pipeline_) publish(pipeline_->flush(), Pairing::kFlushed);
}

}  // namespace ivoa
