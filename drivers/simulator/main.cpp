// ivoa-sim-driver: the simulated robot. Publishes STEREO_IMAGES,
// DEPTH_IMAGE, RIG_CALIBRATION and SIM_GROUND_TRUTH exactly as the real
// drivers would, from a scene file and a seed (one seed + scene = one session).
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/image_t.hpp"
#include "sim_driver.hpp"

namespace {

// 2100-01-01 in us since the epoch: later starts would overflow the utimes of long sessions.
constexpr int64_t kLastStartUtime = 4'102'444'800'000'000;

const std::map<std::string, int32_t> kPixelFormats = {
    {"bgr", ivoa::image_t::PIXEL_FORMAT_BGR},
    {"rgb", ivoa::image_t::PIXEL_FORMAT_RGB},
    {"gray", ivoa::image_t::PIXEL_FORMAT_GRAY},
    {"bayer_rggb", ivoa::image_t::PIXEL_FORMAT_BAYER_RGGB},
    {"bayer_bggr", ivoa::image_t::PIXEL_FORMAT_BAYER_BGGR},
    {"bayer_gbrg", ivoa::image_t::PIXEL_FORMAT_BAYER_GBRG},
    {"bayer_grbg", ivoa::image_t::PIXEL_FORMAT_BAYER_GRBG},
    {"jpeg", ivoa::image_t::PIXEL_FORMAT_JPEG},
    {"png", ivoa::image_t::PIXEL_FORMAT_PNG},
};

// Command-line values that land in the configs only after parsing.
struct CommandLine {
  ivoa::sim::SimDriverConfig driver;
  std::string pixel_format = "bayer_rggb";
  std::string rig_file, save_rig;
  bool fast = false, no_truth = false;
  uint64_t noise_seed = 0;
};

std::vector<std::string> pixel_format_names() {
  std::vector<std::string> names;
  for (const auto& [name, format] : kPixelFormats) names.push_back(name);
  return names;
}

void add_session_options(CLI::App& app, CommandLine& cl) {
  auto& config = cl.driver;
  app.add_option("--scene", config.scene_file, "scene file (YAML, see libs/sim/scenes)")->capture_default_str();
  app.add_option("--seed", config.seed, "scene and trajectory seed (one seed + scene = one session)")
      ->capture_default_str()
      ->check(ivoa::seed_number());
  app.add_option("--noise-seed", cl.noise_seed,
                 "sensor noise realisation: 0 keys the noise by frame alone; another value, same session with other "
                 "noise")
      ->capture_default_str()
      ->check(ivoa::seed_number());
  // A frame every 100 s at the slowest: the trajectory is integrated up to each frame's time.
  app.add_option("--rate", config.rate_hz, "frames per second (0.01 to 1000)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.01, 1000.0));
  auto* realtime = app.add_flag("--realtime", config.realtime, "pace frames by the wall clock (default)");
  app.add_flag("--as-fast-as-possible", cl.fast, "render frames back to back (session time stays frame / rate)")
      ->excludes(realtime);
  app.add_option("--frames", config.frames, "stop after this many frames (0: no limit)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--duration", config.duration_s, "stop after this many seconds of session time (0: no limit)")
      ->check(ivoa::non_negative_number());
  app.add_option("--start-utime", config.start_utime,
                 "utime of frame 0, us since epoch (default: now); frame k is "
                 "at start + k / rate, so sessions are reproducible")
      ->check(CLI::Range(int64_t{0}, kLastStartUtime));  // negative is the struct's "now"
  app.add_option("--rig", cl.rig_file, "render with this rig calibration file instead of the built-in rig");
  app.add_option("--save-rig", cl.save_rig, "write the rig calibration (OpenCV YAML) to this file and go on");
}

void add_output_options(CLI::App& app, CommandLine& cl) {
  auto& config = cl.driver;
  app.add_option("--pixel-format", cl.pixel_format, "published pixel format")
      ->capture_default_str()
      ->check(CLI::IsMember(pixel_format_names()));
  app.add_option("--depth-offset-ms", config.depth_offset_ms, "depth image utime minus stereo utime")
      ->capture_default_str()
      ->check(ivoa::number_in(-1000.0, 1000.0));
  app.add_option("--calibration-period", config.calibration_period_s,
                 "seconds between RIG_CALIBRATION messages (0: with every frame; at most a day)")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 86400));
  app.add_flag("--no-truth", cl.no_truth, "do not publish SIM_GROUND_TRUTH");
  app.add_option("--log", config.log_file,
                 "also write every message to this LCM log, timestamped by message utime "
                 "(bit-identical for the same session)");
  app.add_option("--stereo-channel", config.stereo_channel, "out: stereo pairs (ivoa.stereo_image_t)")
      ->capture_default_str()
      ->check(ivoa::channel_name());
  app.add_option("--depth-channel", config.depth_channel, "out: depth images (ivoa.depth_image_t)")
      ->capture_default_str()
      ->check(ivoa::channel_name());
  app.add_option("--rig-channel", config.rig_channel, "out: rig calibration (ivoa.rig_calibration_t)")
      ->capture_default_str()
      ->check(ivoa::channel_name());
  app.add_option("--truth-channel", config.truth_channel, "out: what each left pixel shows (ivoa.sim_ground_truth_t)")
      ->capture_default_str()
      ->check(ivoa::channel_name());
}

// An output (--log, --save-rig, a file:// --lcm-url to write) that is an
// input (--scene, --rig) or another output: "" if none. The scene file was
// replaced by a log.
std::string output_clash(const CommandLine& cl, const std::string& lcm_url) {
  namespace fs = std::filesystem;
  const std::string url_log = lcm_url.rfind("file://", 0) == 0 && ivoa::replayed_log(lcm_url).empty()
                                  ? lcm_url.substr(7, lcm_url.find('?') - 7)
                                  : "";
  const std::vector<std::pair<std::string, std::string>> outputs{
      {"--log", cl.driver.log_file}, {"--save-rig", cl.save_rig}, {"--lcm-url", url_log}};
  std::vector<std::string> inputs{cl.driver.scene_file};
  if (!cl.rig_file.empty()) inputs.push_back(cl.rig_file);
  std::error_code error;
  for (size_t i = 0; i < outputs.size(); ++i) {
    const auto& [flag, path] = outputs[i];
    if (path.empty()) continue;
    if (const std::string input = ivoa::same_file_among(path, inputs); !input.empty())
      return flag + " " + path + " is the input " + input + ": it would be written over";
    for (size_t j = i + 1; j < outputs.size(); ++j)
      if (!outputs[j].second.empty() &&
          fs::weakly_canonical(path, error) == fs::weakly_canonical(outputs[j].second, error))
        return flag + " and " + outputs[j].first + " name the same file " + path;
  }
  return "";
}

// The rig to render with (--rig, else the built-in one), written to --save-rig
// if asked. Returns an exit code, or -1 to go on.
int prepare_rig(const CommandLine& cl, ivoa::sim::SimulatorConfig& sim_config) {
  try {
    if (!cl.rig_file.empty()) sim_config.rig = ivoa::load_rig_calibration(cl.rig_file);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  if (cl.save_rig.empty()) return -1;
  try {
    ivoa::save_rig_calibration(sim_config.rig, cl.save_rig);
  } catch (const std::exception& e) {
    spdlog::error("cannot write rig calibration {}: {}", cl.save_rig, e.what());
    return ivoa::kExitIoError;
  }
  spdlog::info("wrote rig calibration {}", cl.save_rig);
  return -1;
}

int drive(const ivoa::sim::SimDriverConfig& config, const ivoa::sim::SimulatorConfig& sim_config,
          const std::string& lcm_url, const std::string& status_channel) {
  ivoa::Bus bus(lcm_url);
  ivoa::Heartbeat heartbeat(bus, "sim_driver", status_channel);
  std::unique_ptr<ivoa::sim::SimDriver> driver;
  try {
    driver = std::make_unique<ivoa::sim::SimDriver>(config, sim_config, bus, &heartbeat);
  } catch (const ivoa::sim::SceneSpecError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitIoError;
  } catch (const std::exception& e) {
    // length_error, bad_alloc: a scene that validates but is too large to build.
    spdlog::error("{}: cannot build the scene (seed {}): {}", config.scene_file, config.seed, e.what());
    return ivoa::kExitBadInput;
  }
  spdlog::info("scene {} seed {} at {} Hz ({}), start utime {}, publishing on {}", config.scene_file, config.seed,
               config.rate_hz, config.realtime ? "real time" : "as fast as possible", driver->start_utime(), bus.url());
  int64_t frames = 0;
  try {
    frames = driver->run();
  } catch (const std::runtime_error& e) {  // the --log cannot be written
    spdlog::error("{}", e.what());
    heartbeat.set_state("failed");
    heartbeat.publish_now();
    return ivoa::kExitIoError;
  }
  heartbeat.set_state("stopped");
  heartbeat.publish_now();
  // Frames --realtime skipped because rendering fell behind are part of the session: said here too.
  const int64_t skipped = heartbeat.snapshot().dropped;
  spdlog::info("published {} frames{}{}", frames,
               skipped > 0 ? fmt::format(", skipped {} that rendering was late for (--realtime)", skipped) : "",
               ivoa::stop_requested() ? " (stopped by signal)" : "");
  if (driver->publish_failures() > 0) {
    spdlog::error("{} messages were refused by LCM, not published", driver->publish_failures());
    return ivoa::kExitFailure;
  }
  return ivoa::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Simulated robot: renders a scene along a joystick-like drive and publishes the stereo pair, the depth "
      "image, the rig calibration and the simulator's ground truth"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  CommandLine cl;
  cl.driver.scene_file = std::string(IVOA_SIM_SCENES_DIR) + "/indoor_office.yaml";
  add_session_options(app, cl);
  add_output_options(app, cl);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("sim_driver", common.log_level);
  cl.driver.realtime = !cl.fast;
  cl.driver.publish_truth = !cl.no_truth;
  cl.driver.pixelformat = kPixelFormats.at(cl.pixel_format);

  if (const std::string clash = output_clash(cl, common.lcm_url); !clash.empty()) {
    spdlog::error("{}", clash);
    return ivoa::kExitUsage;
  }
  ivoa::sim::SimulatorConfig sim_config;
  sim_config.noise_seed = cl.noise_seed;
  if (const int code = prepare_rig(cl, sim_config); code >= 0) return code;
  ivoa::install_stop_handlers();
  try {
    return drive(cl.driver, sim_config, common.lcm_url, common.status_channel);
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
