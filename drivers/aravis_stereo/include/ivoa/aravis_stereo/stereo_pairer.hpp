#pragma once
// Pairs left and right frames by timestamp, never by arrival order: one
// camera's frames can sit in a queue while the other's are delivered, so
// the n-th frame to arrive from each side is not the same instant.
//
// A frame is paired with the pending frame of the other camera nearest in
// time if they are at most `tolerance_us` apart. Once a few pairs in a row
// show the same frame-id offset between the cameras, pairing locks onto it:
// a frame then pairs only with the frame numbered to match it (still within
// the tolerance), so one frame delivered late cannot pair with its
// neighbour's partner. Frame ids are unwrapped across the 16-bit GigE wrap.
// Locked pairs whose times keep disagreeing (free-running cameras drift
// apart) unlock it again.
//
// Published pairs move forward in time: a frame older than the last pair on
// its side can never be published and is dropped as out of order. Frames
// that lose their chance (the other camera moved past them, too many
// pending, their partner was lost) are dropped as unpaired. Pure: no
// threads, no clocks.
#include <cstdint>
#include <deque>
#include <optional>

#include "ivoa/aravis_stereo/camera_frame.hpp"
#include "ivoa/aravis_stereo/frame_id_tracker.hpp"

namespace ivoa::aravis_stereo {

struct PairingOptions {
  int64_t tolerance_us = 16000;  // max |t_left - t_right|; at most half a frame period
  size_t max_pending = 4;        // frames kept per side waiting for a partner
  int lock_after_pairs = 3;      // pairs in a row with one frame-id offset before locking onto it; 0 = never
  int unlock_after_rejects = 3;  // locked partners too far apart in time this many times in a row: unlock
};

struct StereoPair {
  CameraFrame left;
  CameraFrame right;
  int64_t skew_us() const { return right.pairing_time_us - left.pairing_time_us; }
};

struct PairingCounts {
  int64_t pairs = 0;           // pairs made
  int64_t unpaired = 0;        // frames dropped without a partner
  int64_t out_of_order = 0;    // frames older than the last pair on their side
  int64_t missed[2] = {0, 0};  // frames a camera numbered but never delivered (frame-id gaps), left/right
  int64_t unlocks = 0;         // times the frame-id lock was given up
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
  bool locked() const { return locked_; }
  const PairingOptions& options() const { return options_; }

 private:
  struct Pending {
    CameraFrame frame;
    int64_t sequence = 0;  // unwrapped frame id
  };
  static int index(Side side) { return side == Side::kLeft ? 0 : 1; }
  std::optional<StereoPair> add_by_time(Pending incoming);
  std::optional<StereoPair> add_by_frame_id(Pending incoming);
  StereoPair emit(Pending a, Pending b);
  void insert_pending(Pending frame);
  void drop_pending_up_to(Side side, int64_t time_us);
  void unlock();

  PairingOptions options_;
  std::deque<Pending> pending_[2];  // sorted by pairing time
  std::optional<int64_t> last_paired_us_[2];
  FrameIdTracker ids_[2];
  PairingCounts counts_;
  bool locked_ = false;
  int64_t offset_ = 0;     // right sequence - left sequence of a pair, when locked
  int64_t candidate_ = 0;  // offset of the recent pairs, while unlocked
  int agreeing_ = 0;       // recent pairs in a row with the candidate offset
  int rejects_ = 0;        // locked partners in a row too far apart in time
};

}  // namespace ivoa::aravis_stereo
