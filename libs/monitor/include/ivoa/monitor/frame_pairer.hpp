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
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace ivoa::monitor {

struct PairingConfig {
  int64_t tolerance_us = 16'667;  // max |stereo - depth| utime (1/60 s)
  // Keep depth frames this long (stream time). Bounds memory on the robot:
  // 640x480 16-bit depth at 30 Hz is 37 MB for 2 s, 184 MB for 10 s.
  int64_t depth_history_us = 2'000'000;
  int64_t max_wait_us = 500'000;  // decide a pending stereo frame once stereo time moves this far past it
};

struct PairingCounters {
  int64_t paired = 0;
  int64_t unmatched_stereo = 0;  // no depth frame within tolerance
  int64_t duplicate_stereo = 0;  // same utime as an earlier stereo frame: ignored
  int64_t duplicate_depth = 0;   // same utime as a buffered depth frame: ignored
  int64_t late_depth = 0;        // older than a depth frame already used: ignored
};

template <class Depth, class Stereo>
class FramePairer {
 public:
  struct Result {
    int64_t stereo_utime;
    Stereo stereo;
    std::optional<int64_t> depth_utime;  // empty: unmatched
    const Depth* depth = nullptr;        // valid until the next add_* / flush call
  };

  explicit FramePairer(PairingConfig config = {}) : config_(config) {}

  std::vector<Result> add_depth(int64_t utime, Depth depth) {
    if (depth_.count(utime)) {
      ++counters_.duplicate_depth;
    } else if (last_used_depth_ && utime < *last_used_depth_) {
      ++counters_.late_depth;
    } else {
      depth_.emplace(utime, std::move(depth));
      newest_depth_ = std::max(newest_depth_.value_or(utime), utime);
    }
    return decide(false);
  }

  std::vector<Result> add_stereo(int64_t utime, Stereo stereo) {
    if (seen_stereo_.count(utime)) {
      ++counters_.duplicate_stereo;
      return decide(false);
    }
    seen_stereo_.insert(utime);
    while (seen_stereo_.size() > 256) seen_stereo_.erase(seen_stereo_.begin());
    pending_.emplace(utime, std::move(stereo));
    newest_stereo_ = std::max(newest_stereo_.value_or(utime), utime);
    return decide(false);
  }

  // Decides every pending stereo frame with what has arrived (end of a log).
  std::vector<Result> flush() { return decide(true); }

  const PairingCounters& counters() const { return counters_; }
  size_t pending() const { return pending_.size(); }

 private:
  std::vector<Result> decide(bool final) {
    // Prune first: results point into depth_ until the next call.
    prune_depth();
    std::vector<Result> out;
    while (!pending_.empty()) {
      auto it = pending_.begin();
      const int64_t t = it->first;
      const bool depth_caught_up = newest_depth_ && *newest_depth_ >= t;
      const bool waited_too_long = newest_stereo_ && *newest_stereo_ - t > config_.max_wait_us;
      if (!final && !depth_caught_up && !waited_too_long) break;
      out.push_back(match(t, std::move(it->second)));
      pending_.erase(it);
    }
    return out;
  }

  Result match(int64_t t, Stereo stereo) {
    Result r{t, std::move(stereo), std::nullopt, nullptr};
    const Depth* best = nullptr;
    int64_t best_utime = 0, best_dt = 0;
    for (const auto& [du, d] : depth_) {
      const int64_t dt = du > t ? du - t : t - du;
      if (dt <= config_.tolerance_us && (!best || dt < best_dt)) {
        best = &d;
        best_utime = du;
        best_dt = dt;
      }
    }
    if (best) {
      r.depth_utime = best_utime;
      r.depth = best;
      last_used_depth_ = std::max(last_used_depth_.value_or(best_utime), best_utime);
      ++counters_.paired;
    } else {
      ++counters_.unmatched_stereo;
    }
    return r;
  }

  void prune_depth() {
    if (!newest_depth_) return;
    while (depth_.size() > 1 && depth_.begin()->first < *newest_depth_ - config_.depth_history_us)
      depth_.erase(depth_.begin());
  }

  PairingConfig config_;
  PairingCounters counters_;
  std::map<int64_t, Depth> depth_;
  std::map<int64_t, Stereo> pending_;
  std::set<int64_t> seen_stereo_;
  std::optional<int64_t> newest_depth_, newest_stereo_, last_used_depth_;
};

}  // namespace ivoa::monitor
