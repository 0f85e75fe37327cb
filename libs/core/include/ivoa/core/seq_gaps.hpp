#pragma once
// Frames a publisher numbered but this process never received: gaps in a
// channel's seq. A udpm subscriber that stalls (a slow frame, SIGSTOP, a
// busy core) loses datagrams once its kernel socket buffer fills, and
// nothing else would count them.
#include <algorithm>
#include <cstdint>
#include <optional>

namespace ivoa {

// Heartbeat counter of the frames that never arrived (SeqGaps).
inline constexpr const char* kFramesMissed = "frames_missed";

class SeqGaps {
 public:
  // A seq this far ahead of the last (about 30 s at 30 Hz), or any seq not
  // ahead of it, is held until the next frame says whether the publisher's
  // numbering really jumped or restarted: one damaged seq must not add
  // billions to the count.
  static constexpr uint64_t kHoldBeyond = 1000;

  // How many frames are newly known to be missing: 0 for the first; for a
  // seq that goes back or jumps far ahead, 0 until the next frame says
  // which it was: if it follows that seq rather than the last one, the
  // publisher restarted (counting starts again there) or its numbering
  // jumped (the jump's gap counts); if not, the one seq was wrong and is
  // forgotten (a damaged seq 2 back once counted the gap back up to it).
  int64_t add(int64_t seq) {
    if (!last_) {
      last_ = seq;
      return 0;
    }
    int64_t missing = 0;
    if (holding_) {
      holding_ = false;
      if (follows(seq, held_) && !follows(seq, *last_)) missing = step(held_);
    }
    if (seq <= *last_ || distance(seq, *last_) > kHoldBeyond) {
      holding_ = true;
      held_ = seq;
      return missing;
    }
    return missing + step(seq);
  }

 private:
  static uint64_t distance(int64_t a, int64_t b) {
    return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                 : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
  }

  static bool follows(int64_t seq, int64_t before) { return seq > before && distance(seq, before) <= kHoldBeyond; }

  int64_t step(int64_t seq) {
    const uint64_t missing = seq > *last_ ? distance(seq, *last_) - 1 : 0;
    last_ = seq;
    return static_cast<int64_t>(std::min<uint64_t>(missing, INT64_MAX));
  }

  std::optional<int64_t> last_;
  // (a flag, not std::optional: GCC 12 warns of a maybe-uninitialized read)
  bool holding_ = false;
  int64_t held_ = 0;
};

}  // namespace ivoa
