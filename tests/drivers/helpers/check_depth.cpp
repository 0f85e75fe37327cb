// ivoa-test-check-depth: subscribes to what ivoa-openni2-kinect publishes
// over real LCM and checks it against what the synthetic OpenNI2 sensor
// (libIvoaSynthDepth) serves: every depth image exactly (a wall at 2000 mm,
// a box at 1000 mm moving 1 px per frame), intrinsics, sequence and timing,
// the colour images and the driver's heartbeat. Writes a JSON summary.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "check_common.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/sim_hardware/synth_depth_scene.hpp"

namespace {

namespace sd = ivoa::sim_hardware::synth_depth;

constexpr int kMaxSkip = 10;  // sensor frames a loaded host may skip between two published ones

struct Flags {
  ivoa::CommonOptions common;
  std::string channel = std::string(ivoa::channels::kDepthImage);
  std::string color_channel = "DEPTH_COLOR";
  int64_t expect = 20;
  double timeout_s = 20;
  bool registered = false;
  std::string status_name = "openni2_kinect";
  bool until_stopped = false;
  std::string ready_file, json_path;
};

class DepthChecker {
 public:
  explicit DepthChecker(const Flags& flags) : flags_(flags) {}

  void on_depth(const ivoa::depth_image_t& msg, const ivoa::ReceiveInfo& info) {
    if (received_ == 0) first_recv_ = info.recv_utime;
    last_recv_ = info.recv_utime;
    ++received_;
    if (last_seq_ >= 0 && msg.seq != last_seq_ + 1) seq_gaps_ += std::max<int64_t>(0, msg.seq - last_seq_ - 1);
    if (last_utime_ > 0 && msg.utime <= last_utime_) ++utime_regressions_;
    fx_ = msg.fx, fy_ = msg.fy, cx_ = msg.cx, cy_ = msg.cy;
    width_ = msg.width, height_ = msg.height;
    source_ = msg.source;
    try {
      check(msg);
    } catch (const std::exception& e) {
      fail("seq " + std::to_string(msg.seq) + ": " + e.what());
    }
    last_seq_ = msg.seq;
    last_utime_ = msg.utime;
  }

  void on_color(const ivoa::image_t& msg, const ivoa::ReceiveInfo&) {
    ++color_;
    color_format_ = msg.pixelformat;
    color_width_ = msg.width;
  }

  int64_t received() const { return received_; }

  ivoa::test::JsonObject json() const {
    ivoa::test::JsonObject o;
    o.set("received", received_);
    o.set("exact", exact_);
    o.set("mismatch", mismatch_);
    o.set("motion_errors", motion_errors_);
    o.set("skipped_frames", skipped_);
    o.set("distinct_positions", distinct_positions_);
    o.set("seq_gaps", seq_gaps_);
    o.set("utime_regressions", utime_regressions_);
    const double span_s = static_cast<double>(last_recv_ - first_recv_) / 1e6;
    o.set("rate_hz", received_ > 1 && span_s > 0 ? static_cast<double>(received_ - 1) / span_s : 0.0);
    o.set("width", width_);
    o.set("height", height_);
    o.set("fx", fx_);
    o.set("fy", fy_);
    o.set("cx", cx_);
    o.set("cy", cy_);
    o.set("source", source_);
    o.set("color_images", color_);
    o.set("color_pixelformat", ivoa::pixelformat_name(color_format_));
    o.set("color_width", color_width_);
    o.set("first_error", first_error_);
    return o;
  }

 private:
  void fail(const std::string& what) {
    ++mismatch_;
    if (first_error_.empty()) first_error_ = what;
  }

  // The box's left edge on a row through it, or -1.
  static int box_left_edge(const cv::Mat& depth) {
    const auto* row = depth.ptr<uint16_t>(sd::kBoxTop + sd::kBoxHeight / 2);
    for (int x = 0; x < depth.cols; ++x)
      if (row[x] == sd::kBoxMm) return x;
    return -1;
  }

  void check(const ivoa::depth_image_t& msg) {
    const cv::Mat depth = ivoa::decode_depth(msg);
    if (depth.cols != sd::kWidth || depth.rows != sd::kHeight)
      return fail("seq " + std::to_string(msg.seq) + ": " + std::to_string(depth.cols) + "x" +
                  std::to_string(depth.rows));
    const int x = box_left_edge(depth);
    if (x < 0) return fail("seq " + std::to_string(msg.seq) + ": no box at 1000 mm");
    // The frame whose box is here; the scene repeats every kBoxTravel frames.
    const int phase = x - sd::kBoxStartX - (flags_.registered ? sd::kRegistrationShiftPx : 0);
    cv::Mat want(sd::kHeight, sd::kWidth, CV_16UC1);
    sd::render_depth(phase, flags_.registered, want.ptr<uint16_t>(), sd::kWidth);
    if (cv::norm(depth, want, cv::NORM_INF) == 0) ++exact_;
    else
      fail("seq " + std::to_string(msg.seq) +
           ": depth differs from the synthetic scene with the box at x=" + std::to_string(x));
    if (last_x_ >= 0 && msg.seq == last_seq_ + 1) {
      // 1 px per sensor frame; a few more when the host skipped frames (the
      // driver counts those as dropped); anything else is wrong.
      const int step = ((x - last_x_) % sd::kBoxTravel + sd::kBoxTravel) % sd::kBoxTravel;
      if (step > 1 && step <= kMaxSkip + 1) {
        skipped_ += step - 1;
      } else if (step != 1) {
        ++motion_errors_;
        if (first_error_.empty())
          first_error_ = "seq " + std::to_string(msg.seq) + ": box moved " + std::to_string(step) + " px, not 1";
      }
    }
    if (x != last_x_) ++distinct_positions_;
    last_x_ = x;
  }

  const Flags& flags_;
  int64_t received_ = 0, exact_ = 0, mismatch_ = 0, motion_errors_ = 0, skipped_ = 0, distinct_positions_ = 0;
  int64_t seq_gaps_ = 0, utime_regressions_ = 0, last_seq_ = -1, last_utime_ = 0, first_recv_ = 0, last_recv_ = 0;
  int last_x_ = -1, width_ = 0, height_ = 0, color_width_ = 0;
  int32_t color_format_ = 0;
  int64_t color_ = 0;
  double fx_ = 0, fy_ = 0, cx_ = 0, cy_ = 0;
  std::string source_, first_error_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Check ivoa-openni2-kinect's output against the synthetic OpenNI2 sensor (integration tests)"};
  Flags f;
  ivoa::add_common_options(app, f.common);
  app.add_option("--channel", f.channel)->capture_default_str();
  app.add_option("--color-channel", f.color_channel)->capture_default_str();
  app.add_option("--expect", f.expect, "stop once this many depth images arrived")->capture_default_str();
  app.add_option("--timeout", f.timeout_s, "give up after this many seconds")->capture_default_str();
  app.add_flag("--registered", f.registered, "expect depth registered to the colour camera");
  app.add_option("--status-name", f.status_name)->capture_default_str();
  app.add_flag("--until-stopped", f.until_stopped, "after the images, wait for the driver's last heartbeat");
  app.add_option("--ready-file", f.ready_file, "created once subscribed");
  app.add_option("--json", f.json_path, "write the summary here")->required();
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("check_depth", f.common.log_level);

  ivoa::Bus bus(f.common.lcm_url);
  DepthChecker checker(f);
  ivoa::test::StatusWatcher status(bus, f.status_name);
  bus.subscribe<ivoa::depth_image_t>(
      f.channel, [&](const ivoa::depth_image_t& m, const ivoa::ReceiveInfo& i) { checker.on_depth(m, i); });
  bus.subscribe<ivoa::image_t>(f.color_channel,
                               [&](const ivoa::image_t& m, const ivoa::ReceiveInfo& i) { checker.on_color(m, i); });
  ivoa::install_stop_handlers();
  bus.handle(0);
  if (!ivoa::write_ready_file(f.ready_file)) return ivoa::kExitIoError;
  const double start = ivoa::monotonic_ms();
  while (!ivoa::stop_requested() && checker.received() < f.expect &&
         ivoa::monotonic_ms() - start < f.timeout_s * 1000) {
    if (bus.handle(50) < 0) break;
  }
  const double linger = ivoa::monotonic_ms();
  while (!ivoa::stop_requested() && ivoa::monotonic_ms() - linger < 1100) bus.handle(50);
  while (f.until_stopped && !status.finished() && !ivoa::stop_requested() &&
         ivoa::monotonic_ms() - start < f.timeout_s * 1000)
    bus.handle(50);
  ivoa::test::JsonObject summary = checker.json();
  summary.set("status", status.json());
  summary.write(f.json_path);
  spdlog::info("checked {} depth images: {}", checker.received(), summary.str());
  return checker.received() >= f.expect ? ivoa::kExitOk : ivoa::kExitFailure;
}
