// ivoa-test-check-stereo: subscribes to what ivoa-aravis-stereo publishes
// over real LCM and checks it against what ivoa-fake-gige-rig served:
// every pair's pixels (exactly, after the same conversion), that left and
// right show the same instant (frame stamps), timing, the rig calibration
// and the driver's heartbeat. Writes a JSON summary for the test script.
#include <cmath>
#include <optional>
#include <set>

#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "check_common.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim_hardware/frame_stamp.hpp"
#include "ivoa/sim_hardware/stereo_scene.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace {

using ivoa::image_t;
using ivoa::sim_hardware::FrameStamp;
using ivoa::sim_hardware::RigCamera;

struct Flags {
  ivoa::CommonOptions common;
  std::string channel = std::string(ivoa::channels::kStereoImages);
  int64_t expect = 20;
  double timeout_s = 30;
  int64_t skip_first = 2;
  std::string camera_format = "BayerRG8";
  std::string stamps = "frame-time";
  ivoa::sim_hardware::PatternOptions pattern;
  std::vector<std::string> left_images, right_images;
  std::string status_name = "aravis_stereo";
  std::string ready_file, json_path;
};

// The pixels of a raw image message, without conversion.
cv::Mat raw_pixels(const image_t& msg) {
  const int channels =
      msg.pixelformat == image_t::PIXEL_FORMAT_BGR || msg.pixelformat == image_t::PIXEL_FORMAT_RGB ? 3 : 1;
  return cv::Mat(msg.height, msg.width, channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(msg.data.data()),
                 static_cast<size_t>(msg.row_stride))
      .clone();
}

// a - b for ticks stamped modulo 2^23, in [-2^22, 2^22).
int64_t tick_difference(uint32_t a, uint32_t b) {
  constexpr int64_t kModulus = int64_t{ivoa::sim_hardware::kStampTickMask} + 1;
  const int64_t d = (int64_t{a} - int64_t{b}) & (kModulus - 1);
  return d >= kModulus / 2 ? d - kModulus : d;
}

class StereoChecker {
 public:
  StereoChecker(const Flags& flags, const ivoa::sim_hardware::StereoScene& scene)
      : flags_(flags),
        scene_(scene),
        sensor_format_(flags.camera_format == "Mono8" ? int32_t{image_t::PIXEL_FORMAT_GRAY}
                                                      : int32_t{image_t::PIXEL_FORMAT_BAYER_RGGB}) {}

  void on_pair(const ivoa::stereo_image_t& msg, const ivoa::ReceiveInfo& info) {
    ++received_;
    if (rig_messages_ == 0) ++pairs_before_rig_;
    if (last_seq_ >= 0 && msg.seq != last_seq_ + 1) seq_gaps_ += std::max<int64_t>(0, msg.seq - last_seq_ - 1);
    if (last_utime_ > 0 && msg.utime <= last_utime_) ++utime_regressions_;
    last_seq_ = msg.seq;
    last_utime_ = msg.utime;
    if (received_ <= flags_.skip_first) return;  // first frames after a camera starts may be off-beat
    if (checked_ == 0) first_recv_ = info.recv_utime;
    last_recv_ = info.recv_utime;
    ++checked_;
    left_format_ = msg.left.pixelformat;
    width_ = msg.left.width;
    height_ = msg.left.height;
    max_skew_us_ = std::max<int64_t>(max_skew_us_, std::llabs(msg.right.utime - msg.left.utime));
    try {
      check(msg);
    } catch (const std::exception& e) {
      fail("pair " + std::to_string(msg.seq) + ": " + e.what());
    }
  }

  void on_rig(const ivoa::rig_calibration_t& msg, const ivoa::ReceiveInfo&) {
    ++rig_messages_;
    rig_name_ = msg.rig_name;
    rig_baseline_ = std::sqrt(msg.stereo_T[0] * msg.stereo_T[0] + msg.stereo_T[1] * msg.stereo_T[1] +
                              msg.stereo_T[2] * msg.stereo_T[2]);
  }

  int64_t checked() const { return checked_; }

  ivoa::test::JsonObject json() const {
    ivoa::test::JsonObject o;
    o.set("received", received_);
    o.set("checked", checked_);
    o.set("content_ok", content_ok_);
    o.set("content_mismatch", content_mismatch_);
    o.set("stamp_missing", stamp_missing_);
    o.set("stamp_mismatch", stamp_mismatch_);
    o.set("off_beat_pairs", off_beat_pairs_);
    o.set("count_slips", count_slips_);
    o.set("first_slip", first_slip_);
    o.set("distinct_ticks", static_cast<int64_t>(ticks_.size()));
    o.set("max_colour_error", max_colour_error_);
    o.set("max_skew_ms", static_cast<double>(max_skew_us_) / 1000.0);
    o.set("seq_gaps", seq_gaps_);
    o.set("utime_regressions", utime_regressions_);
    const double span_s = static_cast<double>(last_recv_ - first_recv_) / 1e6;
    o.set("rate_hz", checked_ > 1 && span_s > 0 ? static_cast<double>(checked_ - 1) / span_s : 0.0);
    o.set("pixelformat", ivoa::pixelformat_name(left_format_));
    o.set("width", width_);
    o.set("height", height_);
    o.set("rig_messages", rig_messages_);
    o.set("pairs_before_rig", pairs_before_rig_);
    o.set("rig_name", rig_name_);
    o.set("rig_baseline", rig_baseline_);
    o.set("first_error", first_error_);
    return o;
  }

 private:
  void fail(const std::string& what) {
    ++content_mismatch_;
    if (first_error_.empty()) first_error_ = what;
  }

  // What the driver should have published for `camera` at `tick`, in the
  // message's pixel format: the served scene through the sensor's format
  // and the same core conversion the driver uses.
  cv::Mat expected(RigCamera camera, const ivoa::sim_hardware::FrameStamp& stamp, cv::Size size,
                   int32_t published_format) const {
    const cv::Mat scene = scene_.render(camera, stamp, size);
    cv::Mat sensor;
    if (sensor_format_ == image_t::PIXEL_FORMAT_GRAY) cv::cvtColor(scene, sensor, cv::COLOR_BGR2GRAY);
    else sensor = ivoa::mosaic_bayer(scene, sensor_format_);
    if (published_format == sensor_format_) return sensor;
    image_t raw;
    raw.width = size.width;
    raw.height = size.height;
    raw.row_stride = size.width;
    raw.pixelformat = sensor_format_;
    raw.data.assign(sensor.data, sensor.data + sensor.total());
    raw.size = static_cast<int32_t>(raw.data.size());
    const bool gray = published_format == image_t::PIXEL_FORMAT_GRAY;
    return ivoa::decode_image(raw, gray ? ivoa::ColorOutput::kGray : ivoa::ColorOutput::kBgr);
  }

  void check(const ivoa::stereo_image_t& msg) {
    const cv::Mat left = raw_pixels(msg.left), right = raw_pixels(msg.right);
    const auto left_tick = ivoa::sim_hardware::read_stamp(left);
    const auto right_tick = ivoa::sim_hardware::read_stamp(right);
    if (!left_tick || !right_tick) {
      ++stamp_missing_;
      return fail("pair " + std::to_string(msg.seq) + ": no frame stamp");
    }
    if (flags_.stamps == "frame-count") check_counts(msg.seq, *left_tick, *right_tick);
    else check_instant(msg.seq, *left_tick, *right_tick);
    ticks_.insert(left_tick->tick);
    bool ok = true;
    for (const auto& [camera, image, tick, format] :
         {std::tuple{RigCamera::kLeft, left, *left_tick, msg.left.pixelformat},
          std::tuple{RigCamera::kRight, right, *right_tick, msg.right.pixelformat}}) {
      const cv::Mat want = expected(camera, tick, image.size(), format);
      const double diff = cv::norm(image, want, cv::NORM_INF);
      if (diff > 0) {
        ok = false;
        fail("pair " + std::to_string(msg.seq) + " " + rig_camera_name(camera) + ": pixels differ by up to " +
             std::to_string(diff) + " from what the fake camera served (" + ivoa::pixelformat_name(format) + ")");
      }
      if (image.channels() == 3 && scene_.is_pattern()) check_colours(camera, image, tick.tick);
    }
    if (ok) ++content_ok_;
  }

  // Free-running stamps are frame times: a true pair shows one tick.
  void check_instant(int64_t seq, const FrameStamp& left, const FrameStamp& right) {
    if (left.off_beat || right.off_beat) {
      // A starved fake camera fired far off its slot: either pairing is defensible.
      ++off_beat_pairs_;
    } else if (left.tick != right.tick) {
      ++stamp_mismatch_;
      if (first_error_.empty())
        first_error_ = "pair " + std::to_string(seq) + ": left shows tick " + std::to_string(left.tick) +
                       ", right tick " + std::to_string(right.tick);
    }
  }

  // Software-trigger stamps are per-camera frame counts. The Aravis fake
  // latches a trigger in one bit, so a camera thread starved for a trigger
  // period merges two triggers into one frame and its count falls one behind
  // for good; the true pairs then differ by a constant. What must hold: the
  // difference changes rarely (once per lost trigger) and pairs are taken
  // together (max_skew_ms), which a pairer that kept a stale offset fails.
  void check_counts(int64_t seq, const FrameStamp& left, const FrameStamp& right) {
    const int64_t offset = tick_difference(right.tick, left.tick);
    if (count_offset_ && offset != *count_offset_) {
      ++count_slips_;
      if (first_slip_.empty())
        first_slip_ = "pair " + std::to_string(seq) + ": right count minus left went from " +
                      std::to_string(*count_offset_) + " to " + std::to_string(offset);
    }
    count_offset_ = offset;
  }

  // Inside the squares demosaicing is exact: a red/blue swap shows here
  // even if the checker's own conversion were wrong the same way.
  void check_colours(RigCamera camera, const cv::Mat& bgr, uint32_t tick) {
    const cv::Mat truth = scene_.render(camera, {tick, false}, bgr.size());
    cv::Mat diff;
    cv::absdiff(bgr, truth, diff);
    const cv::Scalar m = cv::mean(diff, scene_.flat_colour_mask(camera, tick, bgr.size()));
    max_colour_error_ = std::max(max_colour_error_, (m[0] + m[1] + m[2]) / 3.0);
  }

  const Flags& flags_;
  const ivoa::sim_hardware::StereoScene& scene_;
  const int32_t sensor_format_;
  int64_t received_ = 0, checked_ = 0, content_ok_ = 0, content_mismatch_ = 0;
  int64_t stamp_missing_ = 0, stamp_mismatch_ = 0, off_beat_pairs_ = 0, seq_gaps_ = 0, utime_regressions_ = 0;
  int64_t count_slips_ = 0;
  std::optional<int64_t> count_offset_;
  std::string first_slip_;
  int64_t last_seq_ = -1, last_utime_ = 0, first_recv_ = 0, last_recv_ = 0, max_skew_us_ = 0;
  int32_t left_format_ = 0;
  int width_ = 0, height_ = 0;
  double max_colour_error_ = 0;
  std::set<uint32_t> ticks_;
  int64_t rig_messages_ = 0, pairs_before_rig_ = 0;  // the calibration should come first
  std::string rig_name_;
  double rig_baseline_ = 0;
  std::string first_error_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Check ivoa-aravis-stereo's output against the fake GigE rig's scene (integration tests)"};
  Flags f;
  ivoa::add_common_options(app, f.common);
  app.add_option("--channel", f.channel)->capture_default_str();
  app.add_option("--expect", f.expect, "stop once this many pairs were checked")->capture_default_str();
  app.add_option("--timeout", f.timeout_s, "give up after this many seconds")->capture_default_str();
  app.add_option("--skip-first", f.skip_first, "pairs not checked at the start")->capture_default_str();
  app.add_option("--camera-format", f.camera_format, "what the fake cameras serve")
      ->capture_default_str()
      ->check(CLI::IsMember({"BayerRG8", "Mono8"}));
  app.add_option("--stamps", f.stamps,
                 "what the frame stamps count: frame-time (free-running) or frame-count (software trigger)")
      ->capture_default_str()
      ->check(CLI::IsMember({"frame-time", "frame-count"}));
  app.add_option("--disparity", f.pattern.disparity_px)->capture_default_str();
  app.add_option("--speed", f.pattern.speed_px)->capture_default_str();
  app.add_option("--cell", f.pattern.cell_px)->capture_default_str();
  app.add_option("--left-images", f.left_images, "the rig serves these files instead of the pattern");
  app.add_option("--right-images", f.right_images);
  app.add_option("--status-name", f.status_name, "heartbeat of this process goes into the summary")
      ->capture_default_str();
  app.add_option("--ready-file", f.ready_file, "created once subscribed");
  app.add_option("--json", f.json_path, "write the summary here")->required();
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("check_stereo", f.common.log_level);

  const auto scene = f.left_images.empty() ? ivoa::sim_hardware::StereoScene(f.pattern, true)
                                           : ivoa::sim_hardware::StereoScene(f.left_images, f.right_images, true);
  ivoa::Bus bus(f.common.lcm_url);
  StereoChecker checker(f, scene);
  ivoa::test::StatusWatcher status(bus, f.status_name);
  bus.subscribe<ivoa::stereo_image_t>(
      f.channel, [&](const ivoa::stereo_image_t& m, const ivoa::ReceiveInfo& i) { checker.on_pair(m, i); });
  bus.subscribe<ivoa::rig_calibration_t>(
      ivoa::channels::kRigCalibration,
      [&](const ivoa::rig_calibration_t& m, const ivoa::ReceiveInfo& i) { checker.on_rig(m, i); });
  ivoa::install_stop_handlers();
  bus.handle(0);  // udpm joins the group on the first handle
  if (!ivoa::write_ready_file(f.ready_file)) return ivoa::kExitIoError;
  const double start = ivoa::monotonic_ms();
  while (!ivoa::stop_requested() && checker.checked() < f.expect && ivoa::monotonic_ms() - start < f.timeout_s * 1000) {
    if (bus.handle(50) < 0) break;
  }
  // One more second for the heartbeat and rig messages that are on their way.
  const double linger = ivoa::monotonic_ms();
  while (!ivoa::stop_requested() && ivoa::monotonic_ms() - linger < 1100) bus.handle(50);
  ivoa::test::JsonObject summary = checker.json();
  summary.set("status", status.json());
  summary.write(f.json_path);
  spdlog::info("checked {} pairs: {}", checker.checked(), summary.str());
  return checker.checked() >= f.expect ? ivoa::kExitOk : ivoa::kExitFailure;
}
