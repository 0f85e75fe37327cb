#pragma once
// Pairs left and right frames by timestamp, never by arrival order: one
// camera's frames can sit in a queue while the other's are delivered, so
// the n-th frame to arrive from each side is not the same instant.
//
// A frame is paired with the pending frame of the other camera nearest in
// time if they are at most `tolerance_us` apart. Published pairs move
// forward in time: a frame older than the last pair on its side can never
// be published and is dropped as out of order. Frames that lose their
// chance (the other camera has moved past them, or too many are pending)
// are dropped as unpaired. Pure: no threads, no clocks.
#include <cstdint>
#include <deque>
#include <optional>

#include "ivoa/aravis_stereo/camera_frame.hpp"
#include "ivoa/aravis_stereo/frame_id_tracker.hpp"

namespace ivoa::aravis_stereo {

struct PairingOptions {
  int64_t tolerance_us = 16000;  // max |t_left - t_right|; at most half a frame period
  size_t max_pending = 4;        // frames kept per side waiting for a partner
};

struct StereoPair {
  CameraFrame left;
  CameraFrame right;
  int64_t skew_us() const { return right.pairing_time_us - left.pairing_time_us; }
};

struct PairingCounts {
  int64_t pairs = 0;         // pairs made
  int64_t unpaired = 0;      // frames dropped without a partner
  int64_t out_of_order = 0;  // frames older than the last pair on their side
  int64_t missed[2] = {0, 0};  // frames a camera numbered but never delivered (frame-id gaps), left/right
};

class StereoPairer {
 public:
  explicit StereoPairer(const PairingOptions& options = {});

  // Adds a frame; returns the pair it completes, if any.
  std::optional<StereoPair> add(CameraFrame frame);

  // Drops one camera's pending frames and forgets its frame counter and
  // time order (after it reconnects: the counter and clock may restart).
  void reset(Side side);

  const PairingCounts& counts() const { return counts_; }
  size_t pending(Side side) const { return pending_[index(side)].size(); }
  const PairingOptions& options() const { return options_; }

 private:
  static int index(Side side) { return side == Side::kLeft ? 0 : 1; }
  void insert_pending(CameraFrame frame);
  void drop_pending_up_to(Side side, int64_t time_us);

  PairingOptions options_;
  std::deque<CameraFrame> pending_[2];  // sorted by pairing time
  std::optional<int64_t> last_paired_us_[2];
  FrameIdTracker ids_[2];
  PairingCounts counts_;
};

}  // namespace ivoa::aravis_stereo
