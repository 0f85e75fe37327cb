#pragma once
// Keeps a recording from filling its disk. Stereo images arrive at about
// 120 MB/s, so a robot's disk fills within hours, and a disk filled to the
// last block stalls everything else on the machine. Like rosbag record's
// --min-space, the logger stops before an event would leave less than the
// reserve free: the file ends with its last whole event and the logger says
// why. A logger started (or respawned) needs a quarter more than the
// reserve, or it refuses before it creates a file: one respawned as soon as
// a little was freed would only stop again at once.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace ivoa::logger {

struct DiskReserveOptions {
  uint64_t min_free_bytes = 0;  // keep this much free; 0 = none (ivoa-logger's --min-free-mb: 1000 MB)
  double period_s = 1.0;        // between two looks at the disk, at most
  // Free bytes for the log's folder; nothing when they cannot be read.
  // Empty: ivoa::free_bytes_for(the log's path).
  std::function<std::optional<uint64_t>()> free_bytes;
};

class DiskReserve {
 public:
  // Looks once. Throws logio::LogWriteError if the disk holding `log_path`
  // has less free than the reserve and a quarter.
  DiskReserve(std::string log_path, DiskReserveOptions options);

  // Before writing `next_bytes` more (bytes_written: the recording's total
  // so far; now_ms on any monotonic clock). Looks at the disk again when
  // period_s has passed, a quarter of the reserve has been written, or what
  // was free at the last look minus what has been written since would not
  // hold the next event and the reserve. Throws logio::LogWriteError if it
  // would not.
  void check(double now_ms, uint64_t bytes_written, uint64_t next_bytes);

  // The free bytes at the last look; nothing if the disk could not say.
  std::optional<uint64_t> last_free_bytes() const { return last_free_; }

 private:
  void look(double now_ms, uint64_t bytes_written);

  std::string log_path_;
  DiskReserveOptions options_;
  double last_look_ms_ = 0;
  uint64_t bytes_at_last_look_ = 0;
  std::optional<uint64_t> last_free_;
  bool unreadable_warned_ = false;
};

}  // namespace ivoa::logger
