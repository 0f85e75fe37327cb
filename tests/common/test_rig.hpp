#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "ivoa/core/calibration.hpp"

namespace ivoa::test {

// A Jackal-like rig: 960x600 stereo, 0.12 m baseline, 0.3 m high, pitched
// `pitch_deg` down; a 640x480 depth sensor 5 cm above the left camera.
RigCalibration make_test_rig(double pitch_deg = 15.0, bool with_distortion = false);

// The whole file, byte for byte ("" if it cannot be read).
std::string read_file(const std::string& path);

// What a shell command printed, stdout and stderr together, and its exit
// code (-1 if it did not exit normally, e.g. killed by a signal).
struct CommandResult {
  int exit_code = -1;
  std::string output;
};
CommandResult run_command(const std::string& command);

// True once `pid` has exited, reaped or not (a process whose parent died
// is reaped by init, if at all).
bool process_has_ended(int pid);
// Waits up to `limit_s`, polling, for every pid to end; true if they all did.
bool processes_end_within(const std::vector<int>& pids, double limit_s);

// A fresh, empty folder under the system temp dir, removed at destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "ivoa_test");
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace ivoa::test
