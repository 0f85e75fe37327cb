#pragma once
// Watches the free space on the disk an .oni recording is written to.
// OpenNI2's recorder says nothing when its writes fail: on a full disk the
// driver went on streaming and exited 0 with half a recording (a 300 kB
// tmpfs kept 29 of 60 frames). The driver asks this watch once a loop and
// says when space runs low, and when it has run out.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace ivoa::openni2_kinect {

struct DiskWatchLimits {
  uint64_t low_bytes = 512ull << 20;   // warn below this: about 12 minutes of depth at 0.7 MB/s
  uint64_t full_bytes = 256ull << 10;  // below this it is full: a failed write leaves less than a few blocks
  double period_s = 1.0;               // between two looks at the disk
};

class RecordingDiskWatch {
 public:
  // Free bytes for the recording's folder; nothing when they cannot be read.
  using FreeBytes = std::function<std::optional<uint64_t>()>;
  enum class Event { kNone, kLow, kFull };

  // Watches the disk holding `recording`; `free_bytes` defaults to asking
  // the file system for that folder's (as a user may write them: root may
  // also fill the blocks a file system keeps back for it).
  explicit RecordingDiskWatch(std::string recording, DiskWatchLimits limits = {}, FreeBytes free_bytes = {});

  // Looks at the disk if period_s has passed since the last look (now_s on
  // any monotonic clock). Each event is returned once, the first time.
  Event check(double now_s);

  bool full() const { return full_; }
  uint64_t last_free_bytes() const { return last_free_; }
  const std::string& recording() const { return recording_; }

 private:
  std::string recording_;
  DiskWatchLimits limits_;
  FreeBytes free_bytes_;
  std::optional<double> last_look_s_;
  uint64_t last_free_ = 0;
  bool low_ = false, full_ = false;
};

}  // namespace ivoa::openni2_kinect
