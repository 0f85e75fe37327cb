#pragma once
// Keeps a recording from filling its disk. Stereo images arrive at about
// 120 MB/s, so a robot's disk fills within hours, and a disk filled to the
// last block stalls everything else on the machine. Like rosbag record's
// --min-space, the logger stops short of a reserve: the file ends with its
// last whole event and the logger says why; a logger started (or respawned)
// without the room refuses before it creates a file.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace ivoa::logger {

struct DiskReserveOptions {
  uint64_t min_free_bytes = 1'000'000'000;  // stop while this much is still free; 0 = never
  double period_s = 1.0;                    // between two looks at the disk
  // Free bytes for the log's folder; nothing when they cannot be read.
  // Empty: ivoa::free_bytes_for(the log's path).
  std::function<std::optional<uint64_t>()> free_bytes;
};

class DiskReserve {
 public:
  // Looks once. Throws logio::LogWriteError if the disk holding `log_path`
  // already has less free than the reserve.
  DiskReserve(std::string log_path, DiskReserveOptions options);

  // Looks again if period_s has passed since the last look (now_ms on any
  // monotonic clock), or a quarter of the reserve has been written since
  // (bytes_written: the recording's total), whichever comes first: a fast
  // disk must not write through the reserve between two looks. Throws
  // logio::LogWriteError below the reserve.
  void check(double now_ms, uint64_t bytes_written);

 private:
  void look();

  std::string log_path_;
  DiskReserveOptions options_;
  double last_look_ms_ = 0;
  uint64_t bytes_at_last_look_ = 0;
};

}  // namespace ivoa::logger
