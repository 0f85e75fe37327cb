// ivoa-aravis-stereo: the stereo camera driver. Two GenICam cameras (FLIR /
// Point Grey GigE Vision or USB3 Vision) through Aravis -> STEREO_IMAGES,
// plus RIG_CALIBRATION from the rig file and the PROCESS_STATUS heartbeat.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <arv.h>

#include "ivoa/aravis_stereo/aravis_camera.hpp"
#include "ivoa/aravis_stereo/pixel_formats.hpp"
#include "ivoa/aravis_stereo/stereo_driver.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"

namespace {

using namespace ivoa::aravis_stereo;

struct Flags {
  ivoa::CommonOptions common;
  std::string left, right, rig_path;
  AravisCameraConfig camera;
  StereoDriverOptions driver;
  std::string output = "raw";
  std::string timestamps = "mapped";
  bool no_packet_resend = false;
};

// Which cameras, and the image they deliver.
void add_camera_options(CLI::App& app, Flags& f) {
  const char* g = "Cameras";
  app.add_option("--left", f.left, "left camera: IP address, Aravis id (Vendor-Model-Serial), serial number or MAC")
      ->required()
      ->group(g);
  app.add_option("--right", f.right, "right camera: IP address, Aravis id, serial number or MAC")->required()->group(g);
  app.add_option("--rig", f.rig_path, "rig calibration file (OpenCV YAML, see example_rig.yaml)")->required()->group(g);
  auto& c = f.camera;
  app.add_option("--pixel-format", c.pixel_format, std::string("GenICam pixel format: ") + kMappedPixelFormats)
      ->capture_default_str()
      ->group(g);
  app.add_option("--width", c.width, "image width, pixels (0 = keep the camera's)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--height", c.height, "image height, pixels (0 = keep the camera's)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--offset-x", c.offset_x, "region of interest origin, pixels")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--offset-y", c.offset_y, "region of interest origin, pixels")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--frame-rate", c.frame_rate_hz, "frames per second (free-running, or the software-trigger rate)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.1, 500.0))
      ->group(g);
  // Bounded: the camera's int conversion made 1e300 us an exposure of 0, and
  // a NaN gain turned on auto gain without a word.
  app.add_option("--exposure-us", c.exposure_us, "fixed exposure, microseconds (0 = continuous auto exposure)")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 1e8))
      ->group(g);
  app.add_option("--gain", c.gain, "fixed gain in camera units, dB on FLIR (negative = continuous auto gain)")
      ->capture_default_str()
      ->check(ivoa::number_in(-1e3, 1e3))
      ->group(g);
  app.add_option("--trigger", c.trigger, "none (free-running), software, or a hardware line such as Line0")
      ->capture_default_str()
      ->group(g);
}

// How frames travel from the cameras (GigE tuning) and how they are stamped.
void add_transport_options(CLI::App& app, Flags& f) {
  const char* g = "Transport";
  auto& c = f.camera;
  app.add_option("--packet-size", c.packet_size,
                 "GigE packet size, bytes: 9000 with jumbo frames (MTU 9000), 1400 without; 0 = negotiate")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 16384))
      ->group(g);
  app.add_option("--packet-delay-ns", c.packet_delay_ns, "GigE inter-packet delay, ns (0 = keep the camera's)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_flag("--no-packet-resend", f.no_packet_resend, "never ask a GigE camera to resend lost packets")->group(g);
  app.add_option("--throughput-limit", c.throughput_limit,
                 "DeviceLinkThroughputLimit, bytes/s, when both cameras share one link (0 = keep the camera's)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--buffers", c.buffers, "stream buffers per camera")
      ->capture_default_str()
      ->check(ivoa::number_in(2, 64))
      ->group(g);
  app.add_option("--timestamps", f.timestamps,
                 "pair by: mapped (each camera's clock mapped onto the host's: no receive jitter), host (receive "
                 "time), device (the cameras' clocks as they are: only for PTP-synchronised cameras)")
      ->capture_default_str()
      ->check(CLI::IsMember({"mapped", "host", "device"}))
      ->group(g);
}

// Pairing, recovery from a lost camera, and what is published where.
void add_driver_options(CLI::App& app, Flags& f) {
  const char* g = "Pairing, recovery and publishing";
  auto& d = f.driver;
  app.add_option("--output", f.output, "published pixels: raw (the camera's Bayer/mono, smallest), bgr or gray")
      ->capture_default_str()
      ->check(CLI::IsMember({"raw", "bgr", "gray"}))
      ->group(g);
  app.add_option("--pair-tolerance-ms", d.pair_tolerance_ms,
                 "max left/right time difference of a pair, ms (0 = half the frame period)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--frame-timeout", d.worker.frame_timeout_s, "seconds without a frame before a camera is reopened")
      ->capture_default_str()
      ->check(ivoa::positive_number())
      ->group(g);
  app.add_option("--reconnect-initial", d.worker.backoff.initial_s, "first wait between reopen attempts, seconds")
      ->capture_default_str()
      ->check(ivoa::number_in(0.001, 3600))
      ->group(g);
  app.add_option("--reconnect-max", d.worker.backoff.max_s, "longest wait between reopen attempts, seconds")
      ->capture_default_str()
      ->check(ivoa::number_in(0.001, 3600))
      ->group(g);
  app.add_option("--startup-timeout", d.startup_timeout_s,
                 "exit with an error if a camera has not opened after this many seconds (0 = wait forever)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number())
      ->group(g);
  app.add_option("--stereo-channel", d.stereo_channel, "channel for ivoa.stereo_image_t")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_name());
  app.add_option("--rig-channel", d.rig_channel, "channel for ivoa.rig_calibration_t")
      ->capture_default_str()
      ->group(g)
      ->check(ivoa::channel_name());
  app.add_option("--rig-rate", d.rig_rate_hz, "RIG_CALIBRATION publications per second")
      ->capture_default_str()
      ->check(ivoa::number_in(1.0, 100.0))
      ->group(g);
  app.add_option("--source-name", d.source_name, "the 'source' field of published pairs")
      ->capture_default_str()
      ->group(g);
}

void add_options(CLI::App& app, Flags& f) {
  ivoa::add_common_options(app, f.common);
  ivoa::add_status_channel_option(app, f.common.status_channel);
  add_camera_options(app, f);
  add_transport_options(app, f);
  add_driver_options(app, f);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Stereo camera driver: two GenICam cameras (FLIR/Point Grey GigE Vision or USB3 Vision) through "
      "Aravis -> STEREO_IMAGES, RIG_CALIBRATION and PROCESS_STATUS. GigE tuning: " +
      std::string(kGigeTuningHint) + "."};
  Flags f;
  add_options(app, f);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("aravis_stereo", f.common.log_level);
  // The region is set whole or not at all: a width alone was ignored.
  const auto& c = f.camera;
  if ((c.width > 0) != (c.height > 0) || ((c.offset_x > 0 || c.offset_y > 0) && c.width == 0)) {
    spdlog::error(
        "--width and --height set the region together, and --offset-x/--offset-y need them "
        "(given: {}x{} at {}, {})",
        c.width, c.height, c.offset_x, c.offset_y);
    return ivoa::kExitUsage;
  }

  f.driver.output = *parse_output_format(f.output);
  f.driver.frame_rate_hz = f.camera.frame_rate_hz;
  f.driver.software_trigger = f.camera.trigger == "software";
  f.driver.rig_path = f.rig_path;
  f.camera.packet_resend = !f.no_packet_resend;
  f.driver.clock = f.timestamps == "device" ? PairingClock::kDevice
                   : f.timestamps == "host" ? PairingClock::kHost
                                            : PairingClock::kMapped;

  ivoa::RigCalibration rig;
  try {
    rig = ivoa::load_rig_calibration(f.rig_path);
  } catch (const ivoa::CalibrationError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }

  int exit_code = ivoa::kExitOk;
  try {
    ivoa::Bus bus(f.common.lcm_url);
    ivoa::Heartbeat heartbeat(bus, "aravis_stereo", f.common.status_channel);
    AravisCameraConfig left = f.camera, right = f.camera;
    left.device = f.left;
    right.device = f.right;
    StereoDriver driver(bus, heartbeat, rig, f.driver, std::make_unique<AravisCamera>(Side::kLeft, left),
                        std::make_unique<AravisCamera>(Side::kRight, right));
    exit_code = driver.run();
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    exit_code = e.exit_code();
  }
  arv_shutdown();
  return exit_code;
}
