// ivoa-stereo-detector: the stereo obstacle detector (JPP-C or dense SGBM)
// as a process. STEREO_IMAGES + RIG_CALIBRATION in, OBSTACLES_STEREO out.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/stereo/options.hpp"
#include "stereo_detector_node.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Stereo obstacle detector: per query-grid cell FREE / OBSTACLE / UNKNOWN from each stereo pair"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::StereoDetectorOptions options;
  std::string calibration_file, status_channel{ivoa::channels::kProcessStatus};
  app.add_option("--model", options.model, "perception model")
      ->capture_default_str()
      ->check(CLI::IsMember(ivoa::stereo::detector_names()));
  app.add_option("--calibration", calibration_file,
                 "rig calibration file to start with (RIG_CALIBRATION messages replace it)");
  app.add_option("--stereo-channel", options.stereo_channel)->capture_default_str()->group("Channels");
  app.add_option("--calibration-channel", options.calibration_channel)->capture_default_str()->group("Channels");
  app.add_option("--output-channel", options.output_channel)->capture_default_str()->group("Channels");
  app.add_option("--status-channel", status_channel)->capture_default_str()->group("Channels");
  app.add_option("--max-frames", options.max_frames, "exit after publishing this many grids (0: run until stopped)")
      ->capture_default_str();
  ivoa::add_query_grid_options(app, options.grid);
  ivoa::stereo::add_detector_options(app, options.detector);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("stereo-detector", common.log_level);

  try {
    ivoa::stereo::validate(options.detector.jpp);
    ivoa::stereo::validate(options.detector.dense);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  std::optional<ivoa::RigCalibration> initial_rig;
  if (!calibration_file.empty()) {
    try {
      initial_rig = ivoa::load_rig_calibration(calibration_file);
    } catch (const ivoa::CalibrationError& e) {
      spdlog::error("{}", e.what());
      return ivoa::kExitBadInput;
    }
  }
  try {
    ivoa::Bus bus(common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "stereo_detector", status_channel);
    bus.on_decode_error([&](const std::string& what) { heartbeat.bad_input(what); });
    ivoa::StereoDetectorNode node(bus, heartbeat, options);
    if (initial_rig) node.set_calibration(*initial_rig);
    node.start();
    spdlog::info("{} on {} -> {} ({})", options.model, options.stereo_channel, options.output_channel, bus.url());
    const int code = ivoa::run_until_stopped(bus, &heartbeat, [&] {
      if (node.finished()) ivoa::request_stop();
    });
    node.stop();
    heartbeat.publish_now();
    spdlog::info("published {} grids; {} bad inputs", node.published(), heartbeat.bad_input_count());
    return code;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitFailure;
  }
}
