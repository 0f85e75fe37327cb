// ivoa-fake-gige-rig: a simulated GigE Vision stereo pair for tests and
// demos. Two Aravis fake cameras serve a known scene (coloured squares, the
// right view shifted by a known disparity, or image files) over real GVCP
// and GVSP, so the real ivoa-aravis-stereo driver can open and stream from
// them. Run it where 127.0.0.2 exists (tests/harness/in_netns.sh adds it).
//
// SIGUSR1 powers one camera off (it vanishes from the network), SIGUSR2
// powers it on again as a fresh camera; SIGINT/SIGTERM stop the rig.
#include <atomic>
#include <csignal>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/sim_hardware/fake_gige_camera.hpp"

namespace {

using namespace ivoa::sim_hardware;

std::atomic<int> g_power_requests{0};  // +1 power off, +2 power on (last request wins)

extern "C" void on_power_signal(int sig) { g_power_requests = sig == SIGUSR1 ? 1 : 2; }

FakeGigeCameraOptions camera_options(const char* address, const char* serial) {
  FakeGigeCameraOptions options;
  options.address = address;
  options.serial = serial;
  return options;
}

struct Flags {
  ivoa::CommonOptions common;
  FakeGigeCameraOptions left = camera_options("127.0.0.1", "IVOA-LEFT");
  FakeGigeCameraOptions right = camera_options("127.0.0.2", "IVOA-RIGHT");
  std::string cameras = "both";
  PatternOptions pattern;
  std::vector<std::string> left_images, right_images;
  bool no_stamp = false;
  double packet_loss = 0;
  std::string genicam;
  std::string power_cycled = "right";
  std::string ready_file;
  double duration_s = 0;
};

std::unique_ptr<FakeGigeCamera> make_camera(const StereoScene& scene, RigCamera which, const Flags& f) {
  FakeGigeCameraOptions options = which == RigCamera::kLeft ? f.left : f.right;
  options.packet_loss = f.packet_loss;
  options.genicam_xml = f.genicam;
  auto camera = std::make_unique<FakeGigeCamera>(scene, which, options);
  spdlog::info("{} camera serving on {} (serial {}{})", rig_camera_name(which), options.address, options.serial,
               f.packet_loss > 0 ? fmt::format(", losing {:.2f} % of packets", 100 * f.packet_loss) : "");
  return camera;
}

void add_camera_options(CLI::App& app, Flags& f) {
  app.add_option("--left-address", f.left.address, "local address of the left camera")->capture_default_str();
  app.add_option("--right-address", f.right.address, "local address of the right camera")->capture_default_str();
  app.add_option("--left-serial", f.left.serial, "serial number of the left camera")->capture_default_str();
  app.add_option("--right-serial", f.right.serial, "serial number of the right camera")->capture_default_str();
  app.add_option("--cameras", f.cameras, "which cameras to run")
      ->capture_default_str()
      ->check(CLI::IsMember({"both", "left", "right"}));
  app.add_option("--packet-loss", f.packet_loss, "fraction of GVSP packets dropped (the fake never resends)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, 1.0));
  app.add_option("--genicam", f.genicam, "custom GenICam XML for both cameras (default: Aravis' fake camera)")
      ->check(CLI::ExistingFile);  // Aravis served nothing for a missing one, saying "serving"
  app.add_option("--power-cycled", f.power_cycled, "the camera SIGUSR1/SIGUSR2 power off/on")
      ->capture_default_str()
      ->check(CLI::IsMember({"left", "right"}));
  app.add_option("--ready-file", f.ready_file, "create this file once the cameras serve");
  app.add_option("--duration", f.duration_s, "stop after this many seconds (0 = until SIGINT/SIGTERM)")
      ->check(ivoa::non_negative_number());
}

void add_scene_options(CLI::App& app, Flags& f) {
  app.add_option("--disparity", f.pattern.disparity_px, "pattern: right(x) = left(x + disparity), pixels")
      ->capture_default_str();
  app.add_option("--speed", f.pattern.speed_px, "pattern: pixels the texture moves per frame")->capture_default_str();
  app.add_option("--cell", f.pattern.cell_px, "pattern: side of the coloured squares, pixels")->capture_default_str();
  app.add_option("--left-images", f.left_images, "serve these image files (frame tick % count) instead of the pattern");
  app.add_option("--right-images", f.right_images, "right-camera image files, as many as --left-images");
  app.add_flag("--no-stamp", f.no_stamp, "do not write the frame tick into the top-left 256x8 pixels");
}

// Powers the chosen camera off and on as SIGUSR1/SIGUSR2 ask, until a stop
// signal or --duration. Throws if the camera cannot start again.
void serve(const StereoScene& scene, const Flags& f, std::unique_ptr<FakeGigeCamera> (&cameras)[2]) {
  const RigCamera cycled = f.power_cycled == "left" ? RigCamera::kLeft : RigCamera::kRight;
  auto& cycled_camera = cameras[cycled == RigCamera::kLeft ? 0 : 1];
  const double start_ms = ivoa::monotonic_ms();
  while (!ivoa::stop_requested()) {
    if (f.duration_s > 0 && ivoa::monotonic_ms() - start_ms > f.duration_s * 1000.0) break;
    const int request = g_power_requests.exchange(0);
    if (request == 1 && cycled_camera) {
      cycled_camera.reset();
      spdlog::info("{} camera powered off", rig_camera_name(cycled));
    } else if (request == 2 && !cycled_camera) {
      cycled_camera = make_camera(scene, cycled, f);
      spdlog::info("{} camera powered on", rig_camera_name(cycled));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Simulated GigE Vision stereo pair (two Aravis fake cameras serving a known scene). "
      "SIGUSR1 powers one camera off, SIGUSR2 on again."};
  Flags f;
  ivoa::add_common_options(app, f.common);
  add_camera_options(app, f);
  add_scene_options(app, f);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("fake_gige_rig", f.common.log_level);

  std::unique_ptr<StereoScene> scene;
  try {
    scene = f.left_images.empty() ? std::make_unique<StereoScene>(f.pattern, !f.no_stamp)
                                  : std::make_unique<StereoScene>(f.left_images, f.right_images, !f.no_stamp);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return f.left_images.empty() ? ivoa::kExitUsage : ivoa::kExitBadInput;
  }
  if (!f.left_images.empty())  // what the cameras show, which the pattern's checks do not apply to
    spdlog::info("serving {} image pair(s) in turn (the first: {} | {}), resized to the size the driver asks for{}",
                 f.left_images.size(), f.left_images.front(), f.right_images.front(),
                 f.no_stamp ? "" : ", each stamped with its frame number");
  std::unique_ptr<FakeGigeCamera> cameras[2];
  try {
    if (f.cameras != "right") cameras[0] = make_camera(*scene, RigCamera::kLeft, f);
    if (f.cameras != "left") cameras[1] = make_camera(*scene, RigCamera::kRight, f);
    ivoa::install_stop_handlers();
    std::signal(SIGUSR1, on_power_signal);
    std::signal(SIGUSR2, on_power_signal);
    if (!ivoa::write_ready_file(f.ready_file)) return ivoa::kExitIoError;
    serve(*scene, f, cameras);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitFailure;
  }
  for (int i = 0; i < 2; ++i)
    if (cameras[i])
      spdlog::info("{} camera served {} frames ({} off beat: fired over a quarter period late)",
                   rig_camera_name(static_cast<RigCamera>(i)), cameras[i]->frames(), cameras[i]->off_beat_frames());
  return ivoa::kExitOk;
}
