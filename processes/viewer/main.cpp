// ivoa-viewer: the live overlay. Draws each frame's left image with the
// ground grid (label or verdict rings, prediction dots), the P(FP)+P(FN)
// heatmap and the uncertainty heatmap; shows them in a window where there
// is a display (--window), and writes PNGs (--out-dir) and/or a video (--video).
#include <array>
#include <filesystem>
#include <optional>
#include <set>
#include <string>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/viewer/figure_window.hpp"
#include "ivoa/viewer/viewer_node.hpp"

namespace {

void add_output_options(CLI::App& app, ivoa::viewer::ViewerOptions& o) {
  auto& out = o.output;
  app.add_flag("--window", o.window, "show a window (OpenCV highgui) when a display is present");
  app.add_option("--out-dir", out.out_dir, "write figures here as frame_<utime>.png");
  app.add_option("--every", out.every_frames, "a PNG every N figures")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--every-seconds", out.every_seconds, "and at least S seconds apart")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--max-images", out.max_images,
                 "keep only the newest N frame_*.png in --out-dir, an earlier run's too (0: all)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--video", out.video, "also write every figure to this video (.avi, MJPG)");
  app.add_option("--video-fps", out.video_fps, "frame rate written in the video")
      ->capture_default_str()
      ->check(ivoa::number_in(0.1, 1000.0));
  app.add_option("--scale", o.figure.scale, "figure panel size relative to the image")
      ->capture_default_str()
      ->check(ivoa::number_in(0.05, 4.0));
  app.add_option("--uncertainty-max", o.figure.uncertainty_max,
                 "top of the uncertainty panel's colour scale, class variance (0: each frame its own maximum, as "
                 "the paper's figures)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_flag("--dots-given-verdict", o.figure.dots_given_verdict,
               "dots: the prediction given the detector's verdict (default: from the image alone, as the paper)");
  app.add_flag("--every-frame,!--newest-only", o.every_frame,
               "draw every frame in order, reading waits for the drawing (default for file:// logs)");
  app.add_option("--max-figures", o.max_figures, "exit after this many figures (0: run until stopped)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
}

void add_matching_options(CLI::App& app, ivoa::viewer::ViewerOptions& o) {
  const char* g = "Matching";
  app.add_option("--settle-ms", o.matcher.settle_ms,
                 "with no frame complete for this long, draw the best one there is, ms")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::non_negative_number());
  app.add_option("--active-ms", o.matcher.active_ms, "a channel seen this recently is expected in every frame, ms")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::non_negative_number());
  app.add_option("--match-frames", o.matcher.max_frames, "frames kept waiting for their parts")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::number_in(1, 256));
}

void add_channel_options(CLI::App& app, ivoa::viewer::ViewerOptions& o) {
  const char* g = "Channels";
  app.add_option("--stereo-channel", o.stereo_channel, "stereo pairs (ivoa.stereo_image_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--stereo-grid-channel", o.stereo_grid_channel, "stereo grid (ivoa.obstacle_grid_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--depth-grid-channel", o.depth_grid_channel, "depth grid (ivoa.obstacle_grid_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--labels-channel", o.labels_channel, "labels (ivoa.introspection_labels_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
  app.add_option("--introspection-channel", o.introspection_channel, "predictions (ivoa.introspection_t)")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_regex());
}

// Whether to open a window; nullopt (after saying why) when the viewer would
// show nothing at all.
std::optional<bool> choose_window(const ivoa::viewer::ViewerOptions& options) {
  std::string why_no_window;
  const bool window = options.window && ivoa::viewer::window_possible(&why_no_window);
  if (options.output.out_dir.empty() && options.output.video.empty() && !window) {
    spdlog::error("nothing to show{}: give --out-dir DIR and/or --video FILE.avi",
                  options.window ? " (" + why_no_window + ")" : std::string());
    return std::nullopt;
  }
  return window;
}

// The parts a log holds (read from its event headers): each of its frames
// waits for them, also before the first has come (the introspection
// process, warming up, answers the first frames late).
std::array<bool, ivoa::viewer::kNumParts> parts_in_log(const std::string& url, const ivoa::viewer::ViewerOptions& o) {
  using namespace ivoa::viewer;
  std::array<bool, kNumParts> parts{};
  const std::string path = url.substr(7, url.find('?') - 7);  // file://PATH?options
  std::set<std::string> channels;
  if (!std::filesystem::exists(path)) return parts;  // LCM refuses the URL next, saying so
  try {
    ivoa::logio::LogReader reader(path, {/*resync=*/true, /*headers_only=*/true});
    ivoa::logio::LogEvent event;
    while (reader.next(event)) channels.insert(event.channel);  // damage is refused next (run_viewer)
  } catch (const ivoa::logio::LogReadError& e) {
    spdlog::warn("{}; frames wait only for the channels seen so far", e.what());
  }
  parts[kStereoGrid] = channels.count(o.stereo_grid_channel) > 0;
  parts[kDepthGrid] = channels.count(o.depth_grid_channel) > 0;
  parts[kLabels] = channels.count(o.labels_channel) > 0;
  parts[kIntrospection] = channels.count(o.introspection_channel) > 0;
  return parts;
}

// Draws until stopped (or, offline, until the log ends); the exit code.
int run_viewer(const ivoa::CommonOptions& common, const ivoa::viewer::ViewerOptions& options, bool window, bool offline,
               double socket_buffer_mb) {
  ivoa::logio::refuse_a_log_lcm_cannot_replay(common.lcm_url);
  ivoa::Bus bus(common.lcm_url);
  ivoa::Heartbeat heartbeat(bus, "viewer", common.status_channel);
  ivoa::viewer::ViewerNode node(bus, heartbeat, options);
  if (!offline) ivoa::enlarge_receive_buffer(bus, socket_buffer_mb);
  spdlog::info("listening on {}{}{}{}", bus.url(),
               options.output.out_dir.empty() ? "" : "; PNGs in " + options.output.out_dir,
               options.output.video.empty() ? "" : "; video " + options.output.video, window ? "; window" : "");
  const int code = ivoa::run_until_stopped(
      bus, &heartbeat,
      [&] {
        node.tick();
        if (node.done()) ivoa::request_stop();
      },
      50, offline);
  node.finish();
  heartbeat.publish_now();  // with the figures finish() drew
  spdlog::info("{} figures drawn; {}", node.figures(), heartbeat.summary());
  return node.output_failed() ? ivoa::kExitIoError : code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Viewer: left image with the ground grid (label or stereo verdict rings, introspection prediction dots; "
      "TP green, TN blue, FP orange, FN red), P(FP)+P(FN) and uncertainty heatmaps, in a window and/or as "
      "PNG files and video. Exit codes: 0 ok, 1 LCM failure, 2 bad flags, 3 no such log to replay, 4 cannot write "
      "the output."};
  ivoa::CommonOptions common;
  ivoa::viewer::ViewerOptions options;
  double socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  ivoa::add_socket_buffer_option(app, socket_buffer_mb);
  add_output_options(app, options);
  add_matching_options(app, options);
  add_channel_options(app, options);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("viewer", common.log_level);
  const bool offline = common.lcm_url.rfind("file://", 0) == 0;
  if (offline && app.get_option("--every-frame")->count() == 0) options.every_frame = true;
  if (offline) options.matcher.expected = parts_in_log(common.lcm_url, options);
  ivoa::install_stop_handlers();

  const std::optional<bool> window = choose_window(options);
  if (!window) return ivoa::kExitUsage;
  try {
    return run_viewer(common, options, *window, offline, socket_buffer_mb);
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  } catch (const ivoa::viewer::OutputError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitIoError;
  }
}
