#include "ivoa/aravis_stereo/frame_id_tracker.hpp"

namespace ivoa::aravis_stereo {
namespace {

// 16-bit block ids run 1..65535; 0 is reserved and never sent.
constexpr int64_t kBlockIdCount = 65535;

}  // namespace

int64_t FrameIdTracker::delta_from_last(uint64_t frame_id) const {
  if (wide_ids_) return static_cast<int64_t>(frame_id - *last_);
  // Position in the 1..65535 cycle; an id of 0 (not GigE) counts as 65535's successor.
  const int64_t now = frame_id == 0 ? 0 : static_cast<int64_t>(frame_id) - 1;
  const int64_t before = *last_ == 0 ? 0 : static_cast<int64_t>(*last_) - 1;
  int64_t delta = ((now - before) % kBlockIdCount + kBlockIdCount) % kBlockIdCount;
  if (delta > kBlockIdCount / 2) delta -= kBlockIdCount;  // more than half a cycle ahead = behind
  return delta;
}

FrameIdTracker::Step FrameIdTracker::observe(uint64_t frame_id) {
  if (frame_id > 0xFFFF) wide_ids_ = true;
  if (!last_) {
    last_ = frame_id;
    sequence_ = 0;
    return {Kind::kFirst, 0, sequence_};
  }
  const int64_t delta = delta_from_last(frame_id);
  if (delta <= 0) return {Kind::kBackwards, 0, sequence_ + delta};
  last_ = frame_id;
  sequence_ += delta;
  return {Kind::kNext, delta - 1, sequence_};
}

}  // namespace ivoa::aravis_stereo
