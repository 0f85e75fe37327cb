#include "ivoa/aravis_stereo/frame_id_tracker.hpp"

namespace ivoa::aravis_stereo {
namespace {

// 16-bit block ids run 1..65535; 0 is reserved and never sent.
constexpr int64_t kBlockIdCount = 65535;

}  // namespace

FrameIdTracker::Step FrameIdTracker::observe(uint64_t frame_id) {
  if (frame_id > 0xFFFF) wide_ids_ = true;
  if (!last_) {
    last_ = frame_id;
    return {Kind::kFirst, 0};
  }
  int64_t delta = 0;
  if (wide_ids_) {
    delta = static_cast<int64_t>(frame_id - *last_);
  } else {
    // Position in the 1..65535 cycle; an id of 0 (not GigE) counts as 65535's successor.
    const int64_t now = frame_id == 0 ? 0 : static_cast<int64_t>(frame_id) - 1;
    const int64_t before = *last_ == 0 ? 0 : static_cast<int64_t>(*last_) - 1;
    delta = ((now - before) % kBlockIdCount + kBlockIdCount) % kBlockIdCount;
    if (delta > kBlockIdCount / 2) delta -= kBlockIdCount;  // more than half a cycle ahead = behind
  }
  if (delta <= 0) return {Kind::kBackwards, 0};
  last_ = frame_id;
  return {Kind::kNext, delta - 1};
}

}  // namespace ivoa::aravis_stereo
