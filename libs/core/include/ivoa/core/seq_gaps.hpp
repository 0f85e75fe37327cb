#pragma once
// Frames a publisher numbered but this process never received: gaps in a
// channel's seq. A udpm subscriber that stalls (a slow frame, SIGSTOP, a
// busy core) loses datagrams once its kernel socket buffer fills, and
// nothing else would count them.
#include <cstdint>
#include <optional>

namespace ivoa {

// Heartbeat counter of the frames that never arrived (SeqGaps).
inline constexpr const char* kFramesMissed = "frames_missed";

class SeqGaps {
 public:
  // How many frames are missing just before this one: 0 for the first, and
  // 0 when seq goes back (the publisher restarted; counting starts again).
  int64_t add(int64_t seq) {
    const int64_t missing = last_ && seq > *last_ + 1 ? seq - *last_ - 1 : 0;
    last_ = seq;
    return missing;
  }

 private:
  std::optional<int64_t> last_;
};

}  // namespace ivoa
