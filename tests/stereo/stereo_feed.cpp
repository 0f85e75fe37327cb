// ivoa-test-stereo-feed: drives a running ivoa-stereo-detector over real LCM
// and checks what it publishes, for the integration test. Frames before any
// calibration, a calibrated frame, bad input (wrong size, garbage payload), a
// changed calibration; it waits (bounded) for each OBSTACLES_STEREO grid and
// for the detector's PROCESS_STATUS counters. Exit 0 when all checks pass.
#include <cmath>
#include <functional>
#include <optional>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/process_status_t.hpp"
#include "synthetic_scene.hpp"
#include "test_rig.hpp"

namespace {

struct CheckFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

int64_t counter(const ivoa::process_status_t& s, const std::string& name) {
  for (size_t i = 0; i < s.counter_names.size(); ++i)
    if (s.counter_names[i] == name) return s.counter_values[i];
  return 0;
}

class Feed {
 public:
  Feed(const std::string& url, const std::string& process, double timeout_s)
      : bus_(url), process_(process), timeout_ms_(timeout_s * 1000) {
    bus_.subscribe<ivoa::obstacle_grid_t>(
        "OBSTACLES_STEREO", [this](const ivoa::obstacle_grid_t& m, const ivoa::ReceiveInfo&) { grids_.push_back(m); });
    bus_.subscribe<ivoa::process_status_t>("PROCESS_STATUS",
                                           [this](const ivoa::process_status_t& m, const ivoa::ReceiveInfo&) {
                                             if (m.name == process_) status_ = m;
                                           });
    ivoa::test::SyntheticScene room;
    room.boxes.push_back({{4.0, -4.0, 0.0}, {4.2, 4.0, 2.5}, true, 140, 9, 3.0});
    ivoa::test::render_pair(room, rig_a_, left_, right_, 1);
  }

  void run() {
    wait("the detector's first PROCESS_STATUS", [&] { return status_.has_value(); });
    for (int i = 0; i < 3; ++i) {
      publish_frame(1000 + i, left_, right_);
      handle_for(150);
    }
    wait("3 frames before calibration counted as skipped or dropped", [&] {
      return status_->messages_in == 3 && counter(*status_, "frames_without_calibration") + status_->dropped == 3;
    });
    check(grids_.empty(), "no grid may be published before a calibration");
    spdlog::info("frames before calibration: {} skipped, {} dropped", counter(*status_, "frames_without_calibration"),
                 status_->dropped);

    publish_calibration(rig_a_);
    publish_frame(2000, left_, right_);
    const ivoa::obstacle_grid_t first = wait_grid(2000);
    int free = 0, obstacle = 0;
    for (int8_t s : first.state) {
      free += s == ivoa::obstacle_grid_t::STATE_FREE;
      obstacle += s == ivoa::obstacle_grid_t::STATE_OBSTACLE;
    }
    check(first.detector == "jppc" && first.num_cells == 143, "grid 2000: jppc, 11 x 13 cells");
    check(free > 50 && obstacle == 0, "grid 2000: an empty room reads free (" + std::to_string(free) + " free, " +
                                          std::to_string(obstacle) + " obstacle)");

    const cv::Mat small(480, 640, CV_8UC3, cv::Scalar::all(80));
    publish_frame(2500, small, small);
    handle_for(100);
    const uint8_t garbage[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    bus_.publish_raw("STEREO_IMAGES", garbage, sizeof(garbage));
    handle_for(100);
    publish_frame(3000, left_, right_);
    wait_grid(3000);
    wait("bad input (wrong size, garbage) counted", [&] { return status_->bad_input >= 2; });
    spdlog::info("bad input counted: {} (last: {})", status_->bad_input, status_->last_error);

    publish_calibration(ivoa::test::make_test_rig(25.0));
    publish_frame(4000, left_, right_);
    const ivoa::obstacle_grid_t changed = wait_grid(4000);
    const size_t centre = 5 * 13 + 6;
    check(changed.v[centre] < first.v[centre] - 50, "grid 4000 uses the new calibration (the cell's pixel moved)");
    wait("the new calibration counted", [&] { return counter(*status_, "calibrations_applied") == 2; });
    check(status_->state == "running", "state is 'running', got '" + status_->state + "'");
    spdlog::info("all checks passed: {} grids, status in={} out={} dropped={} bad={}", grids_.size(),
                 status_->messages_in, status_->messages_out, status_->dropped, status_->bad_input);
  }

 private:
  void check(bool ok, const std::string& what) {
    if (!ok) throw CheckFailed(what);
  }
  void handle_for(double ms) {
    const double end = ivoa::monotonic_ms() + ms;
    while (ivoa::monotonic_ms() < end) bus_.handle(10);
  }
  void wait(const std::string& what, const std::function<bool()>& done) {
    const double end = ivoa::monotonic_ms() + timeout_ms_;
    while (!(status_ && done())) {
      if (ivoa::monotonic_ms() > end) throw CheckFailed("timed out waiting for " + what);
      bus_.handle(20);
    }
  }
  ivoa::obstacle_grid_t wait_grid(int64_t utime) {
    std::optional<ivoa::obstacle_grid_t> found;
    wait("OBSTACLES_STEREO for utime " + std::to_string(utime), [&] {
      for (const auto& g : grids_)
        if (g.utime == utime) found = g;
      return found.has_value();
    });
    return *found;
  }
  void publish_frame(int64_t utime, const cv::Mat& left, const cv::Mat& right) {
    ivoa::stereo_image_t msg;
    msg.utime = utime;
    msg.seq = seq_++;
    msg.source = "stereo-feed";
    msg.left = ivoa::encode_image(left, ivoa::image_t::PIXEL_FORMAT_BGR, utime);
    msg.right = ivoa::encode_image(right, ivoa::image_t::PIXEL_FORMAT_BGR, utime);
    check(bus_.publish("STEREO_IMAGES", msg), "publish STEREO_IMAGES");
  }
  void publish_calibration(const ivoa::RigCalibration& rig) {
    ivoa::rig_calibration_t msg = ivoa::to_message(rig, ivoa::now_utime());
    check(bus_.publish("RIG_CALIBRATION", msg), "publish RIG_CALIBRATION");
  }

  ivoa::Bus bus_;
  std::string process_;
  double timeout_ms_;
  ivoa::RigCalibration rig_a_ = ivoa::test::make_test_rig(15.0);
  cv::Mat left_, right_;
  int64_t seq_ = 0;
  std::vector<ivoa::obstacle_grid_t> grids_;
  std::optional<ivoa::process_status_t> status_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Drive a running ivoa-stereo-detector and check its output (integration test helper)"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  std::string process = "stereo_detector";
  double timeout_s = 15;
  app.add_option("--process", process, "PROCESS_STATUS name of the detector")->capture_default_str();
  app.add_option("--timeout", timeout_s, "seconds to wait for each expected message")->capture_default_str();
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("stereo-feed", common.log_level);
  try {
    Feed(common.lcm_url, process, timeout_s).run();
  } catch (const CheckFailed& e) {
    spdlog::error("FAILED: {}", e.what());
    return ivoa::kExitFailure;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitFailure;
  }
  return ivoa::kExitOk;
}
