// ivoa-introspection: the CNN that predicts where and how stereo fails, live.
#include <filesystem>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "introspection_node.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"

#ifndef IVOA_DEFAULT_MODEL
#define IVOA_DEFAULT_MODEL ""
#endif

int main(int argc, char** argv) {
  ivoa::introspection::prefer_passive_openmp_wait(argv);
  CLI::App app{"Introspection: heatmaps of predicted stereo failures (TP/TN/FP/FN) with MC-dropout uncertainty"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  std::string model_path = IVOA_DEFAULT_MODEL;
  ivoa::introspection::InferenceConfig config;
  ivoa::IntrospectionNodeOptions options;
  std::string lookup = "nearest";
  app.add_option("--model", model_path, "model file (ivoa-train, or a scripted model)")->capture_default_str();
  app.add_option("--mc-passes", config.mc_passes, "T, Monte-Carlo dropout passes")->capture_default_str();
  app.add_option("--threshold", config.uncertainty_threshold,
                 "announce a prediction when its class variance is at most this (< 0: the model's value)")
      ->capture_default_str();
  app.add_option("--verdict-threshold", config.verdict_uncertainty_threshold,
                 "gate of the predictions given the detector's verdict (variance of P(wrong)); < 0: the model's")
      ->capture_default_str();
  int grid_wait_ms = static_cast<int>(options.grid_wait.count());
  app.add_option("--grid-wait-ms", grid_wait_ms,
                 "after the CNN, how long to wait for the detector's grid of the frame (its verdicts)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--mean-filter", config.mean_filter, "odd window of the heatmap mean filter (1 = off)")
      ->capture_default_str();
  app.add_option("--lookup", lookup, "query cell -> heatmap: nearest cell or bilinear")
      ->capture_default_str()->check(CLI::IsMember({"nearest", "bilinear"}));
  app.add_option("--threads", config.threads, "LibTorch threads")->capture_default_str();
  app.add_option("--device", config.device, "cpu or cuda")->capture_default_str();
  app.add_option("--seed", config.seed, "dropout masks (0 = from the clock)")->capture_default_str();
  app.add_option("--stereo-channel", options.stereo_channel)->capture_default_str()->group("Channels");
  app.add_option("--grid-channel", options.grid_channel, "obstacle grid giving the query cells (\"\" = none)")
      ->capture_default_str()->group("Channels");
  app.add_option("--out-channel", options.out_channel)->capture_default_str()->group("Channels");
  app.add_option("--calibration-channel", options.calibration_channel, "rig calibration (two-view models warp the right image with it)")
      ->capture_default_str()
      ->group("Channels");
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  options.grid_wait = std::chrono::milliseconds(grid_wait_ms);
  config.lookup = lookup == "bilinear" ? ivoa::introspection::QueryLookup::kBilinear
                                       : ivoa::introspection::QueryLookup::kNearest;
  ivoa::init_logging("introspection", common.log_level);
  ivoa::install_stop_handlers();

  std::unique_ptr<ivoa::introspection::IntrospectionModel> model;
  try {
    model = ivoa::introspection::IntrospectionModel::load(model_path, config);
  } catch (const ivoa::introspection::ModelError& e) {
    spdlog::error("refusing the model: {}", e.what());
    return ivoa::kExitBadInput;
  }
  const auto& info = model->info();
  spdlog::info("model {}: {} for '{}', {}px patches at stride {}{}, T = {}, gate {:.5f}", info.id, info.architecture,
               info.detector, info.patch_size, info.stride,
               info.patch_scale > 0 ? fmt::format(", query cells from footprint-scaled patches (x{})", info.patch_scale)
                                    : std::string(),
               config.mc_passes, model->threshold());
  try {
    ivoa::Bus bus(common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "introspection");
    ivoa::IntrospectionNode node(bus, heartbeat, std::move(model), options, config.mc_passes);
    return ivoa::run_until_stopped(bus, &heartbeat, {}, 50, bus.url().rfind("file://", 0) == 0);
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitFailure;
  }
}
