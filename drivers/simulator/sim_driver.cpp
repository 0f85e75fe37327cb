#include "sim_driver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim/messages.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::sim {

SimDriver::SimDriver(SimDriverConfig config, SimulatorConfig simulator_config, Bus& bus, Heartbeat* heartbeat)
    : config_(std::move(config)),
      scene_(generate_scene(load_scene_spec(config_.scene_file), config_.seed)),
      simulator_(scene_, std::move(simulator_config)),
      trajectory_(scene_, config_.seed),
      bus_(bus),
      heartbeat_(heartbeat) {
  if (!(config_.rate_hz > 0)) throw std::invalid_argument("rate must be > 0");
  if (config_.pixelformat == 0) config_.pixelformat = image_t::PIXEL_FORMAT_BAYER_RGGB;
  start_utime_ = config_.start_utime >= 0 ? config_.start_utime : now_utime();
  if (!config_.log_file.empty()) {
    log_ = std::make_unique<lcm::LogFile>(config_.log_file, "w");
    if (!log_->good()) throw std::runtime_error("cannot write LCM log " + config_.log_file);
  }
}

SimDriver::~SimDriver() = default;

int64_t SimDriver::frame_utime(int64_t index) const {
  return start_utime_ + static_cast<int64_t>(std::llround(static_cast<double>(index) * 1e6 / config_.rate_hz));
}

template <class Msg>
void SimDriver::send(const std::string& channel, Msg& msg, int64_t utime) {
  set_counts(msg);
  std::vector<uint8_t> buffer(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  if (!bus_.publish_raw(channel, buffer.data(), buffer.size())) {
    if (publish_failures_++ == 0) spdlog::error("LCM refused a message on {}: not published", channel);
    if (heartbeat_) heartbeat_->add_to_counter("publish_failures", 1);
  }
  if (log_) {
    lcm::LogEvent event;
    event.eventnum = 0;
    event.timestamp = utime;
    event.channel = channel;
    event.datalen = static_cast<int32_t>(buffer.size());
    event.data = buffer.data();
    // Flushed per message, so a full disk is found at the frame it hits.
    if (log_->writeEvent(&event) != 0 || std::fflush(log_->getFilePtr()) != 0)
      throw std::runtime_error("cannot write the LCM log " + config_.log_file + " (disk full?): stopped at utime " +
                               std::to_string(utime));
  }
  if (heartbeat_) heartbeat_->count_out();
}

void SimDriver::publish_calibration(int64_t utime) {
  rig_calibration_t msg = to_message(simulator_.rig(), utime);
  send(config_.rig_channel, msg, utime);
  last_calibration_utime_ = utime;
}

void SimDriver::publish_frame(int64_t index) {
  const double t = static_cast<double>(index) / config_.rate_hz;
  const int64_t utime = frame_utime(index);
  const int64_t depth_utime = utime + static_cast<int64_t>(std::llround(config_.depth_offset_ms * 1e3));
  if (seq_ == 0 || utime - last_calibration_utime_ >= static_cast<int64_t>(config_.calibration_period_s * 1e6))
    publish_calibration(utime);
  RenderRequest request;
  request.stereo_pose = trajectory_.pose_at(t);
  request.depth_pose = trajectory_.pose_at(t + config_.depth_offset_ms * 1e-3);
  request.frame_index = static_cast<uint64_t>(index);
  request.motion = trajectory_.twist_at(t);
  const double started = monotonic_ms();
  const SimFrame frame = simulator_.render(request);
  stereo_image_t stereo = make_stereo_message(frame, utime, seq_, config_.pixelformat);
  send(config_.stereo_channel, stereo, utime);
  depth_image_t depth = make_depth_message(frame, simulator_.rig(), depth_utime, seq_);
  send(config_.depth_channel, depth, depth_utime);
  if (config_.publish_truth) {
    sim_ground_truth_t truth = make_truth_message(frame, scene_, request.stereo_pose, utime, seq_);
    send(config_.truth_channel, truth, utime);
  }
  ++seq_;
  if (heartbeat_) {
    heartbeat_->latency(monotonic_ms() - started);
    heartbeat_->set_counter("frames", seq_);
    heartbeat_->set_counter("exposure_us", static_cast<int64_t>(frame.exposure_ms * 1e3));
  }
}

namespace {

// How many frames k (k * period < duration) a session of this duration has.
int64_t frames_in(double duration_s, double period_s) {
  int64_t n = static_cast<int64_t>(std::ceil(duration_s / period_s));
  while (n > 0 && static_cast<double>(n - 1) * period_s >= duration_s) --n;  // float rounding at the edge
  return n;
}

}  // namespace

int64_t SimDriver::run() {
  if (heartbeat_) heartbeat_->set_state("running");
  const auto wall_start = std::chrono::steady_clock::now();
  const double period_s = 1.0 / config_.rate_hz;
  int64_t index = 0;
  while (!stop_requested()) {
    if (config_.frames > 0 && seq_ >= config_.frames) break;
    if (config_.duration_s > 0 && static_cast<double>(index) * period_s >= config_.duration_s) break;
    if (config_.realtime) {
      // Frame `index` is due at wall_start + index * period. When rendering
      // falls behind, skip to the frame that is due now (never publish stale frames).
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      const auto due_index = static_cast<int64_t>(std::floor(elapsed_s / period_s));
      if (due_index > index) {
        // Counted as skipped: the frames of the session it will not publish (none past its --duration).
        const int64_t session_end = config_.duration_s > 0 ? frames_in(config_.duration_s, period_s) : due_index;
        if (heartbeat_) heartbeat_->count_dropped(std::max<int64_t>(std::min(due_index, session_end) - index, 0));
        index = due_index;
        if (config_.duration_s > 0 && static_cast<double>(index) * period_s >= config_.duration_s) break;
      }
      const auto due = wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>(static_cast<double>(index) * period_s));
      while (!stop_requested() && std::chrono::steady_clock::now() < due) {
        std::this_thread::sleep_until(std::min(due, std::chrono::steady_clock::now() + std::chrono::milliseconds(50)));
        if (heartbeat_) heartbeat_->tick();
      }
      if (stop_requested()) break;
    }
    publish_frame(index);
    ++index;
    if (heartbeat_) heartbeat_->tick();
  }
  if (log_) std::fflush(log_->getFilePtr());
  return seq_;
}

}  // namespace ivoa::sim
