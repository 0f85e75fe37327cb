#pragma once
// Follows one camera's frame counter: unwraps it into a sequence number and
// counts frames that never arrived. GigE Vision 1.x block ids are 16 bits
// and skip 0 (65535 is followed by 1); USB3 Vision and GigE Vision 2
// extended ids are 64 bits. A counter that moves back (a late or repeated
// frame) is reported, not counted as a gap.
#include <cstdint>
#include <optional>

namespace ivoa::aravis_stereo {

class FrameIdTracker {
 public:
  enum class Kind { kFirst, kNext, kBackwards };
  struct Step {
    Kind kind = Kind::kFirst;
    int64_t missed = 0;    // frames skipped between the previous id and this one
    int64_t sequence = 0;  // the id unwrapped: +1 per frame the camera numbered, across wraps
  };

  // Ids are taken as 16-bit block ids until one above 65535 is seen.
  Step observe(uint64_t frame_id);
  // Forget the counter (after a reconnect the camera may restart it).
  void reset() {
    last_.reset();
    sequence_ = 0;
  }

 private:
  int64_t delta_from_last(uint64_t frame_id) const;

  std::optional<uint64_t> last_;
  int64_t sequence_ = 0;
  bool wide_ids_ = false;
};

}  // namespace ivoa::aravis_stereo
