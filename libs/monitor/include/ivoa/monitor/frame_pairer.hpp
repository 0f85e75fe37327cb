#pragma once
// Pairs each stereo frame with the depth image of the same moment: the depth
// frame nearest in utime, if within the tolerance. A pair is only decided
// once no closer depth frame can still arrive (one at or after the stereo
// time has been seen), so a stereo result that arrives before its depth
// frame waits, and nothing is ever paired with a frame that is not the
// nearest. Stereo frames without a partner are reported as unmatched.
//
// Assumes each stream arrives in order of its own utimes (one publisher per
// stream); a depth frame older than one already used is counted as late.
// A frame whose utime jumps more than time_jump_us from its stream's is held
// until the stream's next frame: if that one follows it, the stream's clock
// moved (a gap; or, going back, a log played again, whose frames are then
// paired only with the other stream's frames after its own restart); if not,
// the one frame was wrong and is ignored, so it cannot stop the pairing.
// Ahead, a stream slower than a frame a jump is followed by its own step
// (StreamClock).
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ivoa/monitor/stream_clock.hpp"

namespace ivoa::monitor {

struct PairingConfig {
  int64_t tolerance_us = 16'667;  // max |stereo - depth| utime (1/60 s)
  // Keep depth frames this long (stream time). Bounds memory on the robot:
  // 640x480 16-bit depth at 30 Hz is 37 MB for 2 s, 184 MB for 10 s.
  int64_t depth_history_us = 2'000'000;
  int64_t max_wait_us = 500'000;     // decide a pending stereo frame once stereo time moves this far past it
  int64_t time_jump_us = 1'000'000;  // a utime this far from its stream's newest, either way, is a jump
                                     // (ahead: and over 1.5 of the stream's own steps)
  // Depth restarts kept beyond the stereo stream's, newest first: a depth log
  // looping while the detector is silent would otherwise keep depth_history_us
  // of frames for every play. Stereo frames of a dropped play go unmatched.
  int max_depth_restarts_ahead = 2;  // at least 1: the depth stream's own
};

struct PairingCounters {
  int64_t paired = 0;
  int64_t unmatched_stereo = 0;             // no depth frame within tolerance
  int64_t duplicate_stereo = 0;             // same utime as an earlier stereo frame: ignored
  int64_t duplicate_depth = 0;              // same utime as a buffered depth frame: ignored
  int64_t late_depth = 0;                   // older than a depth frame already used: ignored
  int64_t dropped_depth = 0;                // of a restart too far ahead of the stereo stream's: dropped
  ClockCounters depth_clock, stereo_clock;  // jumps: outliers ignored, restarts followed

  // Another pairer's counts added (a process that rebuilt its pairer for a
  // new calibration reports the session's, not the last pairer's).
  PairingCounters& operator+=(const PairingCounters& o) {
    paired += o.paired, unmatched_stereo += o.unmatched_stereo, duplicate_stereo += o.duplicate_stereo;
    duplicate_depth += o.duplicate_depth, late_depth += o.late_depth, dropped_depth += o.dropped_depth;
    depth_clock.outliers += o.depth_clock.outliers, depth_clock.restarts += o.depth_clock.restarts;
    stereo_clock.outliers += o.stereo_clock.outliers, stereo_clock.restarts += o.stereo_clock.restarts;
    return *this;
  }
};

template <class Depth, class Stereo>
class FramePairer {
 public:
  struct Result {
    int64_t stereo_utime;
    Stereo stereo;
    std::optional<int64_t> depth_utime;  // empty: unmatched
    const Depth* depth = nullptr;        // valid until the next add_* / flush call
    // Unmatched: the nearest depth frame held, depth utime minus stereo
    // (us; < 0: older), to say why; empty when none of its restart is held.
    std::optional<int64_t> nearest_depth_us;
  };

  explicit FramePairer(PairingConfig config = {})
      : config_(config), depth_clock_("depth", config.time_jump_us), stereo_clock_("stereo", config.time_jump_us) {}

  std::vector<Result> add_depth(int64_t utime, Depth depth) {
    for (auto& [t, d, epoch] : depth_clock_.admit(utime, std::move(depth), counters_.depth_clock, clock_event_)) {
      if (depth_.count({epoch, t})) {
        ++counters_.duplicate_depth;
      } else if (last_used_depth_.count(epoch) && t < last_used_depth_[epoch]) {
        ++counters_.late_depth;
      } else {
        depth_.emplace(Key{epoch, t}, std::move(d));
        raise(newest_depth_, epoch, t);
      }
    }
    return decide(false);
  }

  std::vector<Result> add_stereo(int64_t utime, Stereo stereo) {
    for (auto& [t, s, epoch] : stereo_clock_.admit(utime, std::move(stereo), counters_.stereo_clock, clock_event_)) {
      if (!seen_stereo_.insert({epoch, t}).second) {
        ++counters_.duplicate_stereo;
        continue;
      }
      while (seen_stereo_.size() > 256) seen_stereo_.erase(seen_stereo_.begin());
      pending_.emplace(Key{epoch, t}, std::move(s));
      raise(newest_stereo_, epoch, t);
    }
    return decide(false);
  }

  // Decides every pending stereo frame with what has arrived (end of a log).
  // A frame still held for its jump has nothing after it to confirm it: ignored.
  std::vector<Result> flush() {
    depth_clock_.drop_held(counters_.depth_clock, clock_event_);
    stereo_clock_.drop_held(counters_.stereo_clock, clock_event_);
    return decide(true);
  }

  const PairingCounters& counters() const { return counters_; }
  size_t pending() const { return pending_.size(); }
  size_t buffered_depth() const { return depth_.size(); }
  // The last outlier ignored or restart followed (see StreamClock), in a sentence.
  const std::string& last_clock_event() const { return clock_event_; }

 private:
  using Key = std::pair<int, int64_t>;  // (the stream's restarts so far, utime)

  static void raise(std::map<int, int64_t>& newest, int epoch, int64_t t) {
    auto [it, added] = newest.emplace(epoch, t);
    if (!added && t > it->second) it->second = t;
  }

  std::vector<Result> decide(bool final) {
    // Prune first: results point into depth_ until the next call.
    prune_depth();
    std::vector<Result> out;
    while (!pending_.empty()) {
      auto it = pending_.begin();
      const auto [epoch, t] = it->first;
      // Frames of an earlier restart wait for nothing more: their streams have moved on.
      const bool depth_caught_up =
          depth_clock_.epoch() > epoch || (newest_depth_.count(epoch) && newest_depth_[epoch] >= t);
      const bool waited_too_long = stereo_clock_.epoch() > epoch || newest_stereo_[epoch] - t > config_.max_wait_us;
      if (!final && !depth_caught_up && !waited_too_long) break;
      out.push_back(match(epoch, t, std::move(it->second)));
      pending_.erase(it);
    }
    return out;
  }

  Result match(int epoch, int64_t t, Stereo stereo) {
    Result r{t, std::move(stereo), std::nullopt, nullptr, std::nullopt};
    const Depth* best = nullptr;
    int64_t best_utime = 0, best_dt = 0;
    for (auto it = depth_.lower_bound({epoch, t - config_.tolerance_us});
         it != depth_.end() && it->first.first == epoch && it->first.second <= t + config_.tolerance_us; ++it) {
      const int64_t du = it->first.second;
      const int64_t dt = du > t ? du - t : t - du;
      if (!best || dt < best_dt) {
        best = &it->second;
        best_utime = du;
        best_dt = dt;
      }
    }
    if (best) {
      r.depth_utime = best_utime;
      r.depth = best;
      raise(last_used_depth_, epoch, best_utime);
      ++counters_.paired;
    } else {
      ++counters_.unmatched_stereo;
      r.nearest_depth_us = nearest_depth_gap(epoch, t);
    }
    return r;
  }

  std::optional<int64_t> nearest_depth_gap(int epoch, int64_t t) const {
    std::optional<int64_t> gap;
    const auto after = depth_.lower_bound({epoch, t});
    if (after != depth_.end() && after->first.first == epoch) gap = after->first.second - t;
    if (after != depth_.begin()) {
      const auto before = std::prev(after);
      if (before->first.first == epoch && (!gap || t - before->first.second < *gap)) gap = before->first.second - t;
    }
    return gap;
  }

  // Within a restart, the depth frames of the last depth_history_us (at least
  // one); of an earlier restart, none once no stereo frame of it can come; of
  // a restart the stereo stream has not reached, none unless it is one of the
  // newest max_depth_restarts_ahead.
  void prune_depth() {
    const int stereo_epoch = stereo_clock_.epoch();
    const int depth_epoch = depth_clock_.epoch();
    for (auto it = depth_.begin(); it != depth_.end();) {
      const auto [epoch, t] = it->first;
      const bool stereo_moved_on = epoch < stereo_epoch && !has_pending(epoch);
      const bool too_far_ahead =
          epoch > stereo_epoch && epoch <= depth_epoch - std::max(1, config_.max_depth_restarts_ahead);
      const auto next = std::next(it);
      const bool newest_of_its_restart = next == depth_.end() || next->first.first != epoch;
      if (too_far_ahead) ++counters_.dropped_depth;
      if (stereo_moved_on || too_far_ahead ||
          (!newest_of_its_restart && t < newest_depth_[epoch] - config_.depth_history_us))
        it = depth_.erase(it);
      else it = next;
    }
  }

  bool has_pending(int epoch) const {
    const auto it = pending_.lower_bound({epoch, INT64_MIN});
    return it != pending_.end() && it->first.first == epoch;
  }

  PairingConfig config_;
  PairingCounters counters_;
  StreamClock<Depth> depth_clock_;
  StreamClock<Stereo> stereo_clock_;
  std::map<Key, Depth> depth_;
  std::map<Key, Stereo> pending_;
  std::set<Key> seen_stereo_;
  std::map<int, int64_t> newest_depth_, newest_stereo_, last_used_depth_;  // per restart
  std::string clock_event_;
};

}  // namespace ivoa::monitor
