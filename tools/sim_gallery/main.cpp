// ivoa-sim-gallery: renders sample frames from several scenes along their
// trajectories and writes one picture: per scene a row of left, right,
// depth and ground truth (surfaces, with the stereo-failure phenomena as
// coloured stripes).
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/image_files.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"
#include "truth_colors.hpp"

namespace {

using namespace ivoa::sim;

// A moment worth showing: something 0.8-2.5 m straight ahead.
double interesting_time(Trajectory& trajectory, const Scene& scene, double from) {
  for (double t = from; t < from + 90; t += 0.5) {
    const Pose2D p = trajectory.pose_at(t);
    const double ahead = scene.free_distance({p.x, p.y}, p.yaw, 0.3, 5.0);
    if (ahead > 0.8 && ahead < 2.5) return t;
  }
  return from;
}

cv::Mat label(cv::Mat tile, const std::string& text) {
  cv::rectangle(tile, cv::Rect(0, 0, tile.cols, 20), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(tile, text, {6, 14}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return tile;
}

cv::Mat fit(const cv::Mat& image, int width, int height) {
  cv::Mat out;
  cv::resize(image, out, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return out;
}

struct GalleryOptions {
  std::vector<std::string> scenes;
  std::string output = "sim_gallery.png";  // the README's picture: --output docs/sim/gallery.png
  uint64_t seed = 1;
  int tile_width = 400;
  double start_time = 5.0;
};

void add_gallery_options(CLI::App& app, GalleryOptions& o) {
  app.add_option("--scene", o.scenes, "scene files (default: every shipped scene)");
  app.add_option("--seed", o.seed, "scene and trajectory seed")->capture_default_str()->check(ivoa::seed_number());
  app.add_option("--output", o.output, "PNG to write")->capture_default_str();
  app.add_option("--tile-width", o.tile_width, "width of each picture in pixels")
      ->capture_default_str()
      ->check(ivoa::number_in(16, 4000));
  app.add_option("--time", o.start_time, "seconds into the drive to start looking for a frame")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 3600));  // the drive is stepped to it: 1e5 s took 30 s and 600 MB
}

// One scene's row: left (with what was rendered), right, depth, truth.
// Throws on a scene file that cannot be loaded.
cv::Mat gallery_row(const std::string& file, const GalleryOptions& o) {
  const int w = o.tile_width, h = o.tile_width * 600 / 960;
  const Scene scene = generate_scene(load_scene_spec(file), o.seed);
  const Simulator simulator(scene);
  Trajectory trajectory(scene, o.seed);
  const double t = interesting_time(trajectory, scene, o.start_time);
  RenderRequest request;
  request.stereo_pose = request.depth_pose = trajectory.pose_at(t);
  request.frame_index = static_cast<uint64_t>(t * 30);
  request.motion = trajectory.twist_at(t);
  const SimFrame f = simulator.render(request);
  char info[160];
  std::snprintf(info, sizeof info, "%s seed %llu t=%.1fs  exp %.2f ms gain %.1f", scene.name().c_str(),
                static_cast<unsigned long long>(o.seed), t, f.exposure_ms, f.gain);
  spdlog::info("{}", info);
  const cv::Mat tiles[] = {
      label(fit(f.left, w, h), std::string(info)), label(fit(f.right, w, h), "right"),
      label(fit(colorize_depth(f.depth_mm), w, h), "depth sensor (mm)"),
      label(fit(colorize_truth(f.truth_surface, f.truth_phenomena), w, h), "ground truth: surfaces + phenomena")};
  cv::Mat row;
  cv::hconcat(tiles, 4, row);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes a gallery picture of simulated frames (left, right, depth, ground truth) from several scenes"};
  ivoa::CommonOptions common;
  ivoa::add_offline_options(app, common);
  GalleryOptions o;
  add_gallery_options(app, o);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("sim-gallery", common.log_level);
  if (const std::string problem = ivoa::image_file_name_problem(o.output); !problem.empty()) {
    spdlog::error("{}", problem);  // before minutes of rendering
    return ivoa::kExitIoError;
  }
  if (o.scenes.empty())
    for (const char* name : {"indoor_office", "home", "corridor", "polished_lobby", "warehouse", "outdoor_campus",
                             "sidewalk", "wet_parking_lot", "night_plaza"})
      o.scenes.push_back(std::string(IVOA_SIM_SCENES_DIR) + "/" + name + ".yaml");

  std::vector<cv::Mat> rows;
  try {
    for (const auto& file : o.scenes) rows.push_back(gallery_row(file, o));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  rows.push_back(truth_legend(rows.front().cols));
  cv::Mat gallery;
  cv::vconcat(rows, gallery);
  if (std::string error; !ivoa::write_image_file(o.output, gallery, error)) {
    spdlog::error("{}", error);
    return ivoa::kExitIoError;
  }
  spdlog::info("wrote {} ({}x{})", o.output, gallery.cols, gallery.rows);
  return ivoa::kExitOk;
}
