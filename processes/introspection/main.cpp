// ivoa-introspection: the CNN that predicts where and how stereo fails, live.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "introspection_node.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/core/stop_signal.hpp"

#ifndef IVOA_DEFAULT_MODEL
#define IVOA_DEFAULT_MODEL ""
#endif

namespace {

// Values that land in the configs only after parsing.
struct CommandLine {
  std::string model_path = IVOA_DEFAULT_MODEL;
  ivoa::introspection::InferenceConfig config;
  ivoa::IntrospectionNodeOptions options;
  std::string lookup = "nearest";
  int grid_wait_ms = static_cast<int>(options.grid_wait.count());
  std::string warm_up = "model";
  std::string calibration_file;  // --calibration
  double socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
};

// A camera's side, pixels, at most.
constexpr int kMaxFrameSide = 8192;

// "960x600" -> 960 x 600; empty for anything else ("none").
std::optional<cv::Size> frame_size(const std::string& text) {
  int width = 0, height = 0;
  char x = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 || x != 'x' || width <= 0 || height <= 0 ||
      width > kMaxFrameSide || height > kMaxFrameSide)
    return std::nullopt;
  return cv::Size(width, height);
}

void add_model_options(CLI::App& app, CommandLine& cl) {
  auto& config = cl.config;
  app.add_option("--model", cl.model_path, "model file (ivoa-train, or a scripted model)")->capture_default_str();
  app.add_option("--calibration", cl.calibration_file,
                 "rig calibration file a two-view model starts with, so that the first frames need not wait for one "
                 "on the calibration channel (which replaces it)");
  app.add_option("--mc-passes", config.mc_passes, "T, Monte-Carlo dropout passes (1-1000)")
      ->capture_default_str()
      ->check(ivoa::number_in(1, 1000));
  app.add_option("--threshold", config.uncertainty_threshold,
                 "announce a prediction when its class variance is at most this (< 0: the model's value)")
      ->capture_default_str()
      ->check(ivoa::finite_number());  // NaN fell back to the model's gate, inf announced everything
  app.add_option("--verdict-threshold", config.verdict_uncertainty_threshold,
                 "gate of the predictions given the detector's verdict (variance of P(wrong)); < 0: the model's")
      ->capture_default_str()
      ->check(ivoa::finite_number());
  app.add_option("--grid-wait-ms", cl.grid_wait_ms,
                 "after the CNN, how long to wait for the detector's grid of the frame (its verdicts)")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 60000));
  app.add_option("--queue-frames", cl.options.queue_frames,
                 "frames held while the CNN is busy: 1 keeps only the newest (live); more keeps that many, oldest "
                 "first (a log read with ?speed=0); each as received, 1.2 MB a 960x600 Bayer pair")
      ->capture_default_str()
      ->check(ivoa::number_in(1, 1000));
  app.add_option("--mean-filter", config.mean_filter,
                 "odd window of the heatmap mean filter, cells (1 = off; at most 99)")
      ->capture_default_str()
      ->check(ivoa::odd_positive_integer() & ivoa::number_in(1, 99));
  app.add_option("--lookup", cl.lookup, "query cell -> heatmap: nearest cell or bilinear")
      ->capture_default_str()
      ->check(CLI::IsMember({"nearest", "bilinear"}));
  app.add_option("--threads", config.threads, "LibTorch threads (1-256)")
      ->capture_default_str()
      ->check(ivoa::number_in(1, 256));
  app.add_option("--device", config.device, "cpu or cuda")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "cuda"}));
  app.add_option("--seed", config.seed, "dropout masks (0 = from the clock)")
      ->capture_default_str()
      ->check(ivoa::seed_number());
  app.add_option("--warm-up", cl.warm_up,
                 "before listening, run the model once on a blank frame of this size (WxH, the camera's), so the "
                 "first real frame is not delayed by LibTorch's set-up; model: the size it was trained on (960x600 "
                 "if it does not say); none: skip")
      ->capture_default_str()
      ->check([](const std::string& s) {
        return s == "none" || s == "model" || frame_size(s)
                   ? std::string()
                   : "expected WxH (e.g. 960x600, each side at most 8192), model or none";
      });
}

void add_channel_options(CLI::App& app, ivoa::IntrospectionNodeOptions& options) {
  app.add_option("--stereo-channel", options.stereo_channel, "in: stereo pairs (ivoa.stereo_image_t)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_regex());
  app.add_option("--grid-channel", options.grid_channel, "obstacle grid giving the query cells (\"\" = none)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_regex());
  app.add_option("--out-channel", options.out_channel, "out: predictions (ivoa.introspection_t)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_name());
  app.add_option("--calibration-channel", options.calibration_channel,
                 "rig calibration (two-view models warp the right image with it)")
      ->capture_default_str()
      ->group("Channels")
      ->check(ivoa::channel_regex());
}

void log_model(const ivoa::introspection::IntrospectionModel& model, int mc_passes) {
  const auto& info = model.info();
  const std::string trained_on = info.image_sizes.empty()
                                     ? "images of unrecorded size"
                                     : ivoa::introspection::image_sizes_text(info.image_sizes) + " images";
  spdlog::info("model {}: {} for '{}', trained on {}, {}px patches at stride {}{}, T = {}, gate {:.5f}", info.id,
               info.architecture, info.detector, trained_on, info.patch_size, info.stride,
               info.patch_scale > 0 ? fmt::format(", query cells from footprint-scaled patches (x{})", info.patch_scale)
                                    : std::string(),
               mc_passes, model.uncertainty_threshold());
}

// --calibration FILE into the node's options; the exit code if it cannot be read.
std::optional<int> load_initial_calibration(CommandLine& cl, int views) {
  if (cl.calibration_file.empty()) return std::nullopt;
  if (views == 1) {
    spdlog::info("--calibration {}: not used, the model reads the left image alone", cl.calibration_file);
    return std::nullopt;
  }
  try {
    cl.options.initial_calibration = ivoa::load_rig_calibration(cl.calibration_file);
    cl.options.initial_calibration_file = cl.calibration_file;
    spdlog::info("starting with calibration '{}' from {} (one on the calibration channel replaces it)",
                 cl.options.initial_calibration->rig_name, cl.calibration_file);
  } catch (const ivoa::CalibrationError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  ivoa::introspection::tune_libtorch_runtime(argv);
  CLI::App app{"Introspection: heatmaps of predicted stereo failures (TP/TN/FP/FN) with MC-dropout uncertainty"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  CommandLine cl;
  ivoa::add_socket_buffer_option(app, cl.socket_buffer_mb);
  add_model_options(app, cl);
  add_channel_options(app, cl.options);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  cl.options.grid_wait = std::chrono::milliseconds(cl.grid_wait_ms);
  cl.config.lookup = cl.lookup == "bilinear" ? ivoa::introspection::QueryLookup::kBilinear
                                             : ivoa::introspection::QueryLookup::kNearest;
  ivoa::init_logging("introspection", common.log_level);
  ivoa::install_stop_handlers();

  std::unique_ptr<ivoa::introspection::IntrospectionModel> model;
  try {
    model = ivoa::introspection::IntrospectionModel::load(cl.model_path, cl.config);
  } catch (const ivoa::introspection::ModelError& e) {
    spdlog::error("refusing the model: {}", e.what());
    return ivoa::kExitBadInput;
  }
  log_model(*model, cl.config.mc_passes);
  if (const std::optional<int> code = load_initial_calibration(cl, model->info().views); code) return *code;
  cl.options.warm_up =
      cl.warm_up == "model" ? std::optional(ivoa::default_warm_up_size(model->info())) : frame_size(cl.warm_up);
  try {
    ivoa::logio::refuse_a_log_lcm_cannot_replay(common.lcm_url);
    ivoa::logio::warn_that_a_replay_publishes_nothing(common.lcm_url,
                                                      "its predictions (" + cl.options.out_channel + ")");
    ivoa::Bus bus(common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "introspection", common.status_channel);
    ivoa::IntrospectionNode node(bus, heartbeat, std::move(model), cl.options, cl.config.mc_passes);
    ivoa::enlarge_receive_buffer(bus, cl.socket_buffer_mb);
    const int code = ivoa::run_until_stopped(bus, &heartbeat, {}, 50, bus.reads_a_log());
    node.stop();
    heartbeat.publish_now();  // with the frames that were in hand and waiting at the stop
    spdlog::info("stopped: {}", heartbeat.summary());
    return code;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
