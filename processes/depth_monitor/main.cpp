// ivoa-depth-monitor: the supervisor. Turns depth images into per-cell
// obstacle verdicts and labels each stereo verdict TP/TN/FP/FN (Algorithm 1).
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "monitor_node.hpp"

namespace {

void add_monitor_options(CLI::App& app, ivoa::MonitorNodeOptions& o) {
  const char* g = "Depth monitor";
  auto& m = o.monitor;
  app.add_option("--pixel-step", m.pixel_step, "use every n-th depth pixel (1-64)")
      ->capture_default_str()
      ->check(ivoa::number_in(1, 64))
      ->group(g);
  app.add_option("--voxel-size", m.voxel_size, "voxel grid leaf, m")
      ->capture_default_str()
      ->check(ivoa::number_in(0.001, 1.0))
      ->group(g);
  app.add_option("--obstacle-min-height", m.obstacle_min_height, "points higher are obstacles, m")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--obstacle-max-height", m.obstacle_max_height, "points higher are ignored (overhangs), m")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--hole-min-depth", m.hole_min_depth, "points lower than the ground by this are holes, m")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--min-obstacle-points", m.min_obstacle_points, "obstacle voxels within r for OBSTACLE")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--min-hole-points", m.min_hole_points, "hole voxels within r for OBSTACLE")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--min-hole-samples", m.min_hole_samples, "ground-sample rays below the ground for OBSTACLE")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--min-seen-fraction", m.min_seen_fraction, "ground samples seen for FREE (0-1)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, 1.0))
      ->group(g);
  app.add_option("--sync-tolerance-us", o.pairing.tolerance_us, "max |stereo - depth| utime to pair, us")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 60e6))
      ->group(g);
  // A log recorded as fast as possible replays its depth frames in bursts,
  // seconds of stream time ahead of a detector that works through its queue.
  app.add_option("--depth-history-us", o.pairing.depth_history_us,
                 "keep depth frames this long (stream time, behind the newest) for late stereo grids, us")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--time-jump-us", o.pairing.time_jump_us,
                 "a frame this far from its stream's time (ahead: and over 1.5 of the stream's own steps) is held "
                 "until the next says whether the clock moved (a gap, a log played again) or the frame is wrong "
                 "(ignored), us")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
}

void add_channel_options(CLI::App& app, ivoa::MonitorNodeOptions& o) {
  const char* g = "Channels";
  app.add_option("--depth-channel", o.depth_channel, "in: depth images (ivoa.depth_image_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--stereo-channel", o.stereo_channel, "in: the stereo grid to label (ivoa.obstacle_grid_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--calibration-channel", o.calibration_channel, "in: rig calibration (ivoa.rig_calibration_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--depth-out-channel", o.depth_out_channel, "out: the depth grid (ivoa.obstacle_grid_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_name());
  app.add_option("--labels-out-channel", o.labels_out_channel, "out: TP/TN/FP/FN labels (ivoa.introspection_labels_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_name());
}

// The heights are compared once both are parsed (the grid options hold the
// app's parse-complete callback).
bool heights_in_order(const ivoa::monitor::DepthMonitorConfig& m) {
  if (m.obstacle_min_height < m.obstacle_max_height) return true;
  spdlog::error("--obstacle-min-height ({} m) must be below --obstacle-max-height ({} m)", m.obstacle_min_height,
                m.obstacle_max_height);
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Depth monitor: per-cell obstacle verdicts from the depth sensor and Algorithm 1 labels"};
  ivoa::CommonOptions common;
  ivoa::MonitorNodeOptions options;
  double socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
  std::string calibration_file;
  app.add_option("--calibration", calibration_file,
                 "rig calibration file to start with, so that the first frames need not wait for one on the "
                 "calibration channel (which replaces it)");
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  ivoa::add_socket_buffer_option(app, socket_buffer_mb);
  ivoa::add_query_grid_options(app, options.grid);
  add_monitor_options(app, options);
  add_channel_options(app, options);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("depth_monitor", common.log_level);
  if (!heights_in_order(options.monitor)) return ivoa::kExitUsage;
  std::optional<ivoa::RigCalibration> initial_rig;
  try {
    if (!calibration_file.empty()) initial_rig = ivoa::load_rig_calibration(calibration_file);
  } catch (const ivoa::CalibrationError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  ivoa::install_stop_handlers();
  try {
    ivoa::logio::refuse_a_log_lcm_cannot_replay(common.lcm_url);
    ivoa::logio::warn_that_a_replay_publishes_nothing(
        common.lcm_url,
        "its depth grids and labels (" + options.depth_out_channel + ", " + options.labels_out_channel + ")");
    ivoa::Bus bus(common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "depth_monitor", common.status_channel);
    ivoa::MonitorNode node(bus, heartbeat, options);
    if (initial_rig) {
      try {
        node.set_calibration(*initial_rig);
        spdlog::info("started with calibration '{}' from {} (one on the calibration channel replaces it)",
                     initial_rig->rig_name, calibration_file);
      } catch (const std::exception& e) {  // a loaded rig builds; only its maps' memory can fail here
        spdlog::error("{}: unusable calibration: {}", calibration_file, e.what());
        return ivoa::kExitBadInput;
      }
    }
    ivoa::enlarge_receive_buffer(bus, socket_buffer_mb);
    spdlog::info("listening on {} ({} + {} -> {} + {})", bus.url(), options.depth_channel, options.stereo_channel,
                 options.depth_out_channel, options.labels_out_channel);
    const int code = ivoa::run_until_stopped(bus, &heartbeat, {}, 50, bus.reads_a_log());
    node.flush();
    heartbeat.publish_now();  // with the labels flush() published
    spdlog::info("stopped: {}", heartbeat.summary());
    return code;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
