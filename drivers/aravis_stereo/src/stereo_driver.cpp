#include "ivoa/aravis_stereo/stereo_driver.hpp"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::aravis_stereo {
namespace {

PairingOptions pairing_options(const StereoDriverOptions& o) {
  PairingOptions p;
  const double period_ms = o.frame_rate_hz > 0 ? 1000.0 / o.frame_rate_hz : 33.3;
  const double tolerance_ms = o.pair_tolerance_ms > 0 ? o.pair_tolerance_ms : period_ms / 2;
  p.tolerance_us = static_cast<int64_t>(tolerance_ms * 1000.0);
  return p;
}

}  // namespace

struct StereoDriver::State {
  Bus& bus;
  Heartbeat& heartbeat;
  RigCalibration rig;
  StereoDriverOptions options;
  EventQueue events;
  CameraWorker left;
  CameraWorker right;
  StereoPairer pairer;
  ClockMapper clocks[2];
  int64_t seq = 0;
  int64_t incomplete[2] = {0, 0};
  int64_t publish_failures = 0;
  int64_t reported_unpaired = 0;
  bool ever_connected[2] = {false, false};
  bool connected[2] = {false, false};
  bool size_checked[2] = {false, false};
  int fatal_exit_code = -1;

  State(Bus& b, Heartbeat& h, RigCalibration r, const StereoDriverOptions& o, std::unique_ptr<CameraSource> l,
        std::unique_ptr<CameraSource> rt)
      : bus(b),
        heartbeat(h),
        rig(std::move(r)),
        options(o),
        left(Side::kLeft, std::move(l), o.worker, events),
        right(Side::kRight, std::move(rt), o.worker, events),
        pairer(pairing_options(o)) {}

  void check_size_against_rig(const CameraFrame& frame) {
    const int i = static_cast<int>(frame.side);
    if (size_checked[i]) return;
    size_checked[i] = true;
    const CameraIntrinsics& cam = frame.side == Side::kLeft ? rig.left : rig.right;
    if (cam.width != frame.width || cam.height != frame.height)
      spdlog::warn(
          "{} camera delivers {}x{} but the rig calibration {} is for {}x{}: geometry downstream will be "
          "wrong; calibrate at this size or set --width/--height",
          side_name(frame.side), frame.width, frame.height, options.rig_path, cam.width, cam.height);
  }

  // Sets the time the frame is paired by. Mapped camera time is also the
  // better capture time to publish; raw device clocks are not epoch-based,
  // so host receive time is published with them (and with kHost).
  void apply_clock(CameraFrame& frame) {
    switch (options.clock) {
      case PairingClock::kHost: frame.pairing_time_us = frame.utime; break;
      case PairingClock::kDevice: frame.pairing_time_us = frame.device_time_us; break;
      case PairingClock::kMapped:
        frame.utime = frame.pairing_time_us =
            clocks[static_cast<int>(frame.side)].map(frame.device_time_us, frame.utime);
        break;
    }
  }

  void on_frame(CameraFrame&& frame) {
    heartbeat.count_in();
    check_size_against_rig(frame);
    apply_clock(frame);
    auto pair = pairer.add(std::move(frame));
    if (!pair) return;
    try {
      stereo_image_t msg = make_stereo_message(*pair, options.output, seq, options.source_name);
      if (!bus.publish(options.stereo_channel, msg)) {
        ++publish_failures;
        spdlog::error("LCM refused stereo pair {} on {}", seq, options.stereo_channel);
        return;
      }
    } catch (const ImageError& e) {
      heartbeat.bad_input(e.what());
      return;
    }
    ++seq;
    heartbeat.count_out();
    heartbeat.latency(static_cast<double>(now_utime() - pair->left.utime) / 1000.0);
  }

  void update_state() {
    if (connected[0] && connected[1]) heartbeat.set_state("running");
    else if (!connected[0] && !connected[1]) heartbeat.set_state("waiting for both cameras");
    else
      heartbeat.set_state(std::string("waiting for the ") + side_name(connected[0] ? Side::kRight : Side::kLeft) +
                          " camera");
  }

  void on_event(CameraEvent& event) {
    const int i = static_cast<int>(event.side);
    switch (event.type) {
      case CameraEvent::Type::kFrame: on_frame(std::move(event.frame)); break;
      case CameraEvent::Type::kIncomplete:
        ++incomplete[i];
        heartbeat.bad_input(std::string(side_name(event.side)) + " camera " + event.detail + "; dropped");
        break;
      case CameraEvent::Type::kConnected:
        pairer.reset(event.side);  // its frame counter and clock may have restarted
        clocks[i].reset();
        connected[i] = ever_connected[i] = true;
        update_state();
        break;
      case CameraEvent::Type::kDisconnected:
        connected[i] = false;
        update_state();
        break;
      case CameraEvent::Type::kFatal: fatal_exit_code = kExitUsage; break;
    }
  }

  void publish_counters() {
    const PairingCounts& c = pairer.counts();
    const int64_t overflow = events.overflow_drops();
    if (c.unpaired + overflow > reported_unpaired) {
      heartbeat.count_dropped(c.unpaired + overflow - reported_unpaired);
      reported_unpaired = c.unpaired + overflow;
    }
    heartbeat.set_counter("pairs", c.pairs);
    heartbeat.set_counter("incomplete", incomplete[0] + incomplete[1]);
    heartbeat.set_counter("incomplete_left", incomplete[0]);
    heartbeat.set_counter("incomplete_right", incomplete[1]);
    heartbeat.set_counter("unpaired", c.unpaired);
    heartbeat.set_counter("out_of_order", c.out_of_order);
    heartbeat.set_counter("missed_left", c.missed[0]);
    heartbeat.set_counter("missed_right", c.missed[1]);
    heartbeat.set_counter("disconnects", left.disconnects() + right.disconnects());
    heartbeat.set_counter("reconnects", left.reconnects() + right.reconnects());
    heartbeat.set_counter("pairing_unlocks", c.unlocks);
    heartbeat.set_counter("queue_overflow", overflow);
    heartbeat.set_counter("publish_failures", publish_failures);
  }

  void publish_rig() {
    rig_calibration_t msg = to_message(rig, now_utime());
    bus.publish(options.rig_channel, msg);
  }
};

StereoDriver::StereoDriver(Bus& bus, Heartbeat& heartbeat, RigCalibration rig, const StereoDriverOptions& options,
                           std::unique_ptr<CameraSource> left, std::unique_ptr<CameraSource> right)
    : state_(std::make_unique<State>(bus, heartbeat, std::move(rig), options, std::move(left), std::move(right))) {}

StereoDriver::~StereoDriver() = default;

int StereoDriver::run() {
  State& s = *state_;
  install_stop_handlers();
  s.update_state();
  // The calibration goes out before the cameras open, so the consumers (and
  // the depth sensor's monitor) have it before the first frame.
  s.publish_rig();
  const double start_ms = monotonic_ms();
  s.left.start();
  s.right.start();
  const double rig_period_ms = 1000.0 / std::max(s.options.rig_rate_hz, 0.1);
  const double trigger_period_ms = 1000.0 / std::max(s.options.frame_rate_hz, 0.1);
  double next_rig_ms = start_ms + rig_period_ms;
  double next_trigger_ms = start_ms;
  int exit_code = kExitOk;
  spdlog::info("pairing left/right frames within {:.1f} ms; publishing {} on {} and the rig on {} at {:.1f} Hz",
               static_cast<double>(s.pairer.options().tolerance_us) / 1000.0,
               s.options.output == OutputFormat::kRaw   ? "raw"
               : s.options.output == OutputFormat::kBgr ? "BGR"
                                                        : "gray",
               s.options.stereo_channel, s.options.rig_channel, s.options.rig_rate_hz);

  while (!stop_requested()) {
    double wait_ms = 50;
    if (s.options.software_trigger) wait_ms = std::clamp(next_trigger_ms - monotonic_ms(), 0.0, wait_ms);
    for (CameraEvent& event : s.events.take(std::chrono::milliseconds(static_cast<int>(wait_ms)))) s.on_event(event);
    if (s.fatal_exit_code >= 0) {
      exit_code = s.fatal_exit_code;
      break;
    }
    const double now = monotonic_ms();
    // Trigger only when both cameras listen, or their frame counts diverge.
    if (s.options.software_trigger && now >= next_trigger_ms && s.connected[0] && s.connected[1]) {
      s.left.trigger();
      s.right.trigger();
      next_trigger_ms = std::max(next_trigger_ms + trigger_period_ms, now);
    }
    if (now >= next_rig_ms) {
      s.publish_rig();
      next_rig_ms = std::max(next_rig_ms + rig_period_ms, now);
    }
    if (s.options.startup_timeout_s > 0 && !(s.ever_connected[0] && s.ever_connected[1]) &&
        now - start_ms > s.options.startup_timeout_s * 1000.0) {
      spdlog::error(
          "cameras not ready after {:.0f} s (left {}, right {}); check the addresses, cabling and "
          "network (each camera's messages say why)",
          s.options.startup_timeout_s, s.ever_connected[0] ? "open" : "NOT open",
          s.ever_connected[1] ? "open" : "NOT open");
      exit_code = kExitFailure;
      break;
    }
    s.publish_counters();
    s.heartbeat.tick();
  }
  if (stop_requested()) spdlog::info("stopping (signal {})", stop_signal());
  s.left.request_stop();
  s.right.request_stop();
  s.left.stop();
  s.right.stop();
  s.publish_counters();
  s.heartbeat.set_state("stopped");
  s.heartbeat.publish_now();
  const PairingCounts& c = s.pairer.counts();
  spdlog::info("published {} pairs; dropped {} incomplete, {} unpaired, {} out-of-order frames; {} reconnects", s.seq,
               s.incomplete[0] + s.incomplete[1], c.unpaired, c.out_of_order,
               s.left.reconnects() + s.right.reconnects());
  return exit_code;
}

}  // namespace ivoa::aravis_stereo
