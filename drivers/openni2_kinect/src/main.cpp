// ivoa-openni2-kinect: the supervisory depth sensor driver. A Kinect-like
// sensor (or an .oni recording of one) through OpenNI2 -> DEPTH_IMAGE
// (millimetres, with intrinsics), optionally DEPTH_COLOR, and the
// PROCESS_STATUS heartbeat. Can record what it streams to an .oni file.
#include <cstdlib>
#include <optional>

#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/openni2_kinect/openni_camera.hpp"
#include "ivoa/openni2_kinect/recording_disk_watch.hpp"

namespace {

using namespace ivoa::openni2_kinect;

// The depth sensor's colour camera (optional).
const std::string kDefaultColorChannel{ivoa::channels::kDepthColor};

struct Flags {
  ivoa::CommonOptions common;
  OpenNiOptions camera;
  std::string rig_path;
  std::string depth_channel = std::string(ivoa::channels::kDepthImage);
  std::string color_channel = kDefaultColorChannel;
  std::string color_format = "rgb";
  std::string source_name = "openni2";
  int64_t max_frames = 0;
  double frame_timeout_s = 5.0;
  bool lossless_color = false;
};

void add_options(CLI::App& app, Flags& f) {
  ivoa::add_common_options(app, f.common);
  ivoa::add_status_channel_option(app, f.common.status_channel);
  app.add_option("--device", f.camera.device, "ANY_DEVICE (the first sensor), an OpenNI2 device URI, or an .oni file")
      ->capture_default_str();
  app.add_flag("--color", f.camera.color, "also publish the 640x480 colour image");
  app.add_flag("--register", f.camera.register_depth,
               "depth-to-colour registration: depth in the colour camera's frame (its intrinsics are published)");
  app.add_option("--rig", f.rig_path, "rig calibration file: use its K_depth instead of the field-of-view intrinsics");
  app.add_option("--record", f.camera.record_path,
                 "also record the streams to this .oni file (strftime patterns such as %Y%m%d-%H%M%S are expanded "
                 "at start; if it exists, to the first free FILE-1.oni, FILE-2.oni, ...: never overwritten)");
  app.add_flag("--record-lossless-color", f.lossless_color, "record colour losslessly (about 30x larger)");
  app.add_option("--max-frames", f.max_frames, "stop after this many depth frames (0 = no limit)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--playback-speed", f.camera.playback_speed, ".oni only: 1 = real time, 0 = as fast as possible")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_flag("--loop", f.camera.loop, ".oni only: start again at the end instead of exiting");
  app.add_option("--frame-timeout", f.frame_timeout_s, "exit with an error after this many seconds without depth")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--depth-channel", f.depth_channel, "channel for ivoa.depth_image_t")
      ->capture_default_str()
      ->check(ivoa::channel_name());
  app.add_option("--color-channel", f.color_channel, "channel for the colour image (ivoa.image_t)")
      ->capture_default_str()
      ->check(ivoa::channel_name());
  app.add_option("--color-format", f.color_format, "colour image wire format")
      ->capture_default_str()
      ->check(CLI::IsMember({"rgb", "jpeg"}));
  app.add_option("--source-name", f.source_name, "the 'source' field of published images")->capture_default_str();
}

// Intrinsics from the rig file if given, else from the reported field of
// view, else (a device that reports none) Kinect v1's nominal one.
PinholeIntrinsics choose_intrinsics(const OpenNiCamera& camera, const Flags& f, std::string* origin) {
  const int w = camera.depth_width(), h = camera.depth_height();
  if (!f.rig_path.empty()) {
    *origin = "K_depth of " + f.rig_path;
    return intrinsics_from_rig(ivoa::load_rig_calibration(f.rig_path), w, h, f.rig_path);
  }
  PinholeIntrinsics k;  // the camera checked its mode and field of view on opening
  if (camera.depth_fov_intrinsics(&k)) {
    *origin = camera.registered() ? "the colour camera's field of view (registered)" : "the depth field of view";
    return k;
  }
  *origin = "Kinect v1's nominal field of view (the device reports none)";
  return intrinsics_from_fov(w, h, kKinectV1DepthHfovRad, kKinectV1DepthVfovRad);
}

class Publisher {
 public:
  Publisher(ivoa::Bus& bus, ivoa::Heartbeat& heartbeat, const Flags& flags, const PinholeIntrinsics& k)
      : bus_(bus), heartbeat_(heartbeat), flags_(flags), k_(k) {}

  void depth(const DepthFrame& frame) {
    heartbeat_.count_in();
    if (last_index_ > 0 && frame.frame_index > last_index_ + 1)
      heartbeat_.count_dropped(frame.frame_index - last_index_ - 1);
    last_index_ = frame.frame_index;
    ivoa::depth_image_t msg = ivoa::encode_depth(frame.depth_mm, k_.fx, k_.fy, k_.cx, k_.cy, ivoa::now_utime());
    msg.seq = depth_seq_++;
    msg.source = flags_.source_name;
    if (bus_.publish(flags_.depth_channel, msg)) heartbeat_.count_out();
    heartbeat_.set_counter("depth_frames", depth_seq_);
  }

  void color(const ColorFrame& frame) {
    const int64_t utime = ivoa::now_utime();
    ivoa::image_t msg;
    if (flags_.color_format == "jpeg") {
      cv::Mat bgr;
      cv::cvtColor(frame.rgb, bgr, cv::COLOR_RGB2BGR);
      msg = ivoa::encode_image(bgr, ivoa::image_t::PIXEL_FORMAT_JPEG, utime);
    } else {
      // The sensor's RGB bytes as they are: no conversion.
      msg.utime = utime;
      msg.width = frame.rgb.cols;
      msg.height = frame.rgb.rows;
      msg.row_stride = frame.rgb.cols * 3;
      msg.pixelformat = ivoa::image_t::PIXEL_FORMAT_RGB;
      msg.data.assign(frame.rgb.data, frame.rgb.data + frame.rgb.total() * 3);
      msg.size = static_cast<int32_t>(msg.data.size());
    }
    if (bus_.publish(flags_.color_channel, msg)) heartbeat_.count_out();
    heartbeat_.set_counter("color_frames", ++color_count_);
  }

  int64_t depth_frames() const { return depth_seq_; }

 private:
  ivoa::Bus& bus_;
  ivoa::Heartbeat& heartbeat_;
  const Flags& flags_;
  const PinholeIntrinsics k_;
  int64_t depth_seq_ = 0;
  int64_t color_count_ = 0;
  int last_index_ = 0;
};

// Reads and publishes the frame that is ready; false for a bad frame
// (counted and reported in the heartbeat, and skipped).
bool publish_ready(OpenNiCamera& camera, OpenNiCamera::Ready ready, Publisher& publisher, ivoa::Heartbeat& heartbeat) {
  try {
    if (ready == OpenNiCamera::Ready::kDepth) publisher.depth(camera.read_depth());
    else publisher.color(camera.read_color());
    return true;
  } catch (const BadFrame& e) {
    heartbeat.bad_input(camera.description() + ": " + e.what());
    return false;
  }
}

// Says when the recording's disk runs low, and when it is full: OpenNI2's
// recorder then drops what it cannot write without an error, so the
// recording is incomplete (exit 4 at the end; the depth stream goes on).
void watch_recording_disk(RecordingDiskWatch& watch, const Publisher& publisher, ivoa::Heartbeat& heartbeat) {
  const auto event = watch.check(ivoa::monotonic_ms() / 1000.0);
  const double free_mb = static_cast<double>(watch.last_free_bytes()) / (1 << 20);
  if (event == RecordingDiskWatch::Event::kLow) {
    spdlog::warn("{}: {:.1f} MB left on its disk; the recording stops when it is full", watch.recording(), free_mb);
  } else if (event == RecordingDiskWatch::Event::kFull) {
    spdlog::error(
        "{}: its disk is full ({:.1f} MB left) after {} depth frames; OpenNI2 drops what it cannot write without "
        "saying so, so the recording is incomplete from about here (depth is still published)",
        watch.recording(), free_mb, publisher.depth_frames());
    heartbeat.set_counter("recording_disk_full", 1);
  }
}

int stream(OpenNiCamera& camera, Publisher& publisher, ivoa::Heartbeat& heartbeat, const Flags& f) {
  heartbeat.set_state("running");
  std::optional<RecordingDiskWatch> disk_watch;
  if (!camera.record_path().empty()) disk_watch.emplace(camera.record_path());
  double last_depth_ms = ivoa::monotonic_ms();
  int64_t bad_depth_frames = 0;
  while (!ivoa::stop_requested()) {
    const auto ready = camera.wait(100);
    if (ready == OpenNiCamera::Ready::kEndOfRecording) {
      spdlog::info("end of recording {} after {} depth frames", f.camera.device, publisher.depth_frames());
      // A recording none of whose depth frames could be read is bad input, not a session.
      if (publisher.depth_frames() == 0 && bad_depth_frames > 0) {
        spdlog::error("{}: none of its {} depth frames could be read", f.camera.device, bad_depth_frames);
        return ivoa::kExitBadInput;
      }
      break;
    }
    if (ready == OpenNiCamera::Ready::kDepth) {
      if (publish_ready(camera, ready, publisher, heartbeat)) {
        last_depth_ms = ivoa::monotonic_ms();
        if (f.max_frames > 0 && publisher.depth_frames() >= f.max_frames) break;
      } else {
        ++bad_depth_frames;
      }
    } else if (ready == OpenNiCamera::Ready::kColor) {
      publish_ready(camera, ready, publisher, heartbeat);
    } else if (ivoa::monotonic_ms() - last_depth_ms > f.frame_timeout_s * 1000.0) {
      spdlog::error("no depth frame for {:.1f} s from {}; is the sensor still connected?", f.frame_timeout_s,
                    camera.description());
      return ivoa::kExitFailure;
    }
    if (disk_watch) watch_recording_disk(*disk_watch, publisher, heartbeat);
    heartbeat.tick();
  }
  return disk_watch && disk_watch->full() ? ivoa::kExitIoError : ivoa::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Depth sensor driver: a Kinect-like sensor or an .oni recording through OpenNI2 -> DEPTH_IMAGE "
      "(millimetres, with intrinsics), optional colour, PROCESS_STATUS. A Kinect v1 needs libfreenect's "
      "OpenNI2 driver (not packaged by Debian; see drivers/openni2_kinect/README.md)."};
  Flags f;
  add_options(app, f);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("openni2_kinect", f.common.log_level);
  ivoa::install_stop_handlers();  // before OpenNI2 starts: a signal while it opens the device still exits cleanly
  f.camera.lossy_color = !f.lossless_color;
  if (!f.camera.record_path.empty()) {
    const std::string pattern = f.camera.record_path;
    f.camera.record_path = ivoa::expand_time_pattern(pattern);
    if (f.camera.record_path.empty()) {
      spdlog::error("--record: the file name pattern '{}' expands to nothing", pattern);
      return ivoa::kExitUsage;
    }
  }

  try {
    ivoa::Bus bus(f.common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "openni2_kinect", f.common.status_channel);
    int exit_code = ivoa::kExitOk;
    try {
      OpenNiCamera camera(f.camera);
      std::string origin;
      const PinholeIntrinsics k = choose_intrinsics(camera, f, &origin);
      spdlog::info("{}: publishing {}x{} depth on {} (fx {:.1f}, fy {:.1f}, cx {:.1f}, cy {:.1f} from {}){}",
                   camera.description(), camera.depth_width(), camera.depth_height(), f.depth_channel, k.fx, k.fy, k.cx,
                   k.cy, origin, f.camera.color ? " and colour on " + f.color_channel : "");
      Publisher publisher(bus, heartbeat, f, k);
      exit_code = stream(camera, publisher, heartbeat, f);
    } catch (const DeviceError& e) {
      spdlog::error("{}", e.what());
      exit_code = e.exit_code();
      if (exit_code == ivoa::kExitBadInput && is_recording_path(f.camera.device)) {
        heartbeat.set_state("failed");
        heartbeat.publish_now();
        spdlog::shutdown();
        std::_Exit(exit_code);  // past OpenNI2's teardown (OpenNiCamera's constructor)
      }
    } catch (const ivoa::CalibrationError& e) {
      spdlog::error("{}", e.what());
      exit_code = ivoa::kExitBadInput;
    }
    heartbeat.set_state(exit_code == ivoa::kExitOk ? "stopped" : "failed");
    heartbeat.publish_now();
    return exit_code;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
