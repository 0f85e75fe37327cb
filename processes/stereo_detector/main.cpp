// ivoa-stereo-detector: the stereo obstacle detector (JPP-C or dense SGBM)
// as a process. STEREO_IMAGES + RIG_CALIBRATION in, OBSTACLES_STEREO out.
#include <optional>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/stereo/options.hpp"
#include "stereo_detector_node.hpp"

namespace {

struct DetectorFlags {
  ivoa::StereoDetectorOptions options;
  std::string calibration_file;
  double socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
};

void add_detector_flags(CLI::App& app, DetectorFlags& f) {
  ivoa::StereoDetectorOptions& o = f.options;
  ivoa::add_socket_buffer_option(app, f.socket_buffer_mb);
  app.add_option("--model", o.model, "perception model")
      ->capture_default_str()
      ->check(CLI::IsMember(ivoa::stereo::detector_names()));
  app.add_option("--calibration", f.calibration_file,
                 "rig calibration file to start with (RIG_CALIBRATION messages replace it)");
  app.add_option("--stereo-channel", o.stereo_channel, "in: stereo pairs (ivoa.stereo_image_t)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_regex());
  app.add_option("--calibration-channel", o.calibration_channel, "in: rig calibration (ivoa.rig_calibration_t)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_regex());
  app.add_option("--output-channel", o.output_channel, "out: obstacle grid (ivoa.obstacle_grid_t)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_name());
  app.add_option("--max-frames", o.max_frames, "exit after publishing this many grids (0: run until stopped)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--queue-frames", o.queue_frames,
                 "frames held while the detector is busy: 1 keeps only the newest (live); more keeps that many, "
                 "oldest first (recording a simulator that renders ahead)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  ivoa::add_query_grid_options(app, o.grid);
  ivoa::stereo::add_detector_options(app, o.detector);
}

// Checks the detector's settings and loads the starting calibration, if
// any; on failure logs why and returns the exit code.
std::optional<int> prepare(const DetectorFlags& f, std::optional<ivoa::RigCalibration>& initial_rig) {
  try {
    ivoa::stereo::validate(f.options.detector.jpp);
    ivoa::stereo::validate(f.options.detector.dense);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  if (f.calibration_file.empty()) return std::nullopt;
  try {
    initial_rig = ivoa::load_rig_calibration(f.calibration_file);
  } catch (const ivoa::CalibrationError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  return std::nullopt;
}

int run_detector(const ivoa::CommonOptions& common, const DetectorFlags& f,
                 const std::optional<ivoa::RigCalibration>& initial_rig) {
  ivoa::StereoDetectorOptions o = f.options;
  try {
    ivoa::logio::refuse_a_log_lcm_cannot_replay(common.lcm_url);
    o.publish_failures_expected = ivoa::logio::warn_that_a_replay_publishes_nothing(
        common.lcm_url, "its obstacle grids (" + o.output_channel + ")");
    ivoa::Bus bus(common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "stereo_detector", common.status_channel);
    bus.on_decode_error([&](const std::string& what) { heartbeat.bad_input(what); });
    ivoa::StereoDetectorNode node(bus, heartbeat, o);
    if (initial_rig) node.set_calibration(*initial_rig);
    node.start();
    ivoa::enlarge_receive_buffer(bus, f.socket_buffer_mb);
    spdlog::info("{} on {} -> {} ({})", o.model, o.stereo_channel, o.output_channel, bus.url());
    const int code = ivoa::run_until_stopped(
        bus, &heartbeat,
        [&] {
          if (node.finished()) ivoa::request_stop();
        },
        50, bus.reads_a_log());
    node.stop();
    heartbeat.set_state("stopped");  // the worker may have said "running" since, on its last frames
    heartbeat.publish_now();
    spdlog::info("stopped: {}", heartbeat.summary());
    return code;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Stereo obstacle detector: per query-grid cell FREE / OBSTACLE / UNKNOWN from each stereo pair"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  DetectorFlags flags;
  add_detector_flags(app, flags);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("stereo-detector", common.log_level);
  std::optional<ivoa::RigCalibration> initial_rig;
  if (const auto code = prepare(flags, initial_rig)) return *code;
  return run_detector(common, flags, initial_rig);
}
