#include "test_rig.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <random>
#include <thread>

namespace ivoa::test {

RigCalibration make_test_rig(double pitch_deg, bool with_distortion) {
  RigCalibration rig;
  rig.rig_name = "test_rig";
  auto camera = [&](const std::string& name, int w, int h, double f) {
    CameraIntrinsics c;
    c.name = name;
    c.width = w;
    c.height = h;
    c.K << f, 0, w / 2.0 - 0.5, 0, f, h / 2.0 + 0.25, 0, 0, 1;
    if (with_distortion && name != "depth") c.D = {-0.12, 0.05, 0.0005, -0.0003, 0.0};
    return c;
  };
  rig.left = camera("left", 960, 600, 600.0);
  rig.right = camera("right", 960, 600, 602.0);
  rig.stereo_R = Eigen::AngleAxisd(0.004, Eigen::Vector3d::UnitY()).toRotationMatrix();
  rig.stereo_T = {-0.12, 0.0005, 0.0};
  const double pitch = pitch_deg * M_PI / 180.0;
  rig.left_to_robot.linear() = optical_to_robot(pitch);
  rig.left_to_robot.translation() = Eigen::Vector3d(0.0, 0.06, 0.30);
  rig.depth = camera("depth", 640, 480, 570.0);
  rig.depth_to_robot.linear() = optical_to_robot(pitch);
  rig.depth_to_robot.translation() = Eigen::Vector3d(0.0, 0.0, 0.35);
  return rig;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TempDir::TempDir(const std::string& prefix) {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof(buffer), pipe)) > 0) r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

bool process_has_ended(int pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(stat, text)) return true;
  const size_t paren = text.rfind(')');  // the name may hold spaces and parentheses
  return paren == std::string::npos || paren + 2 >= text.size() || text[paren + 2] == 'Z';
}

bool processes_end_within(const std::vector<int>& pids, double limit_s) {
  for (int i = 0; i < limit_s * 20; ++i) {
    if (std::all_of(pids.begin(), pids.end(), process_has_ended)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return std::all_of(pids.begin(), pids.end(), process_has_ended);
}

}  // namespace ivoa::test
