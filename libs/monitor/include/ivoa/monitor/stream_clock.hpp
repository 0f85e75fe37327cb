#pragma once
// Follows one stream's utimes for FramePairer. A frame whose utime is more
// than a jump away from the stream's newest is held back until the next
// frame: if that one follows it (within a jump of it, not of the newest),
// the clock moved and both are taken, a move back counting as a restart (a
// log played again, a sensor's clock reset) that starts a new epoch; if not,
// the held frame is ignored as an outlier. One wrong utime then cannot move
// the stream's time away from every frame after it.
//
// A stream slower than one frame a jump (a depth sensor throttled to
// 0.5 Hz) steps more than a jump every frame. So ahead of the newest frame
// a jump is also more than 1.5 times the stream's own step: the shortest of
// its last three steps between frames taken as they came (a jump followed
// is no step). Until three are known, a held frame ahead is followed by a
// next frame that steps on from it by no more than 1.5 times as far as it
// stepped. A wrong utime ahead by under 1.5 steps is then taken as a frame
// (it pairs with nothing), as one within a jump always was.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace ivoa::monitor {

struct ClockCounters {
  int64_t outliers = 0;  // one frame far from its stream's time, not followed by the next: ignored
  int64_t restarts = 0;  // the stream's time went back more than a jump and stayed: followed
};

template <class Frame>
class StreamClock {
 public:
  struct Admitted {
    int64_t utime;
    Frame frame;
    int epoch;  // restarts before it
  };

  StreamClock(const char* stream, int64_t jump_us) : stream_(stream), jump_us_(jump_us) {}

  // The frames to take now, in order: none while this one is held for its
  // jump, the held one and this one once this one follows it. `event` gets
  // a sentence when a held frame is ignored or a restart followed.
  std::vector<Admitted> admit(int64_t utime, Frame frame, ClockCounters& counters, std::string& event) {
    std::vector<Admitted> out;
    if (held_) {
      if (follows(utime, held_->first) && !near(utime, *newest_)) {
        take_held(counters, event, out);
        take(utime, std::move(frame), out);  // it follows the held one: a step of the stream
        return out;
      }
      drop_held(counters, event);
    }
    if (newest_ && !near(utime, *newest_)) {
      held_.emplace(utime, std::move(frame));
      return out;
    }
    take(utime, std::move(frame), out);
    return out;
  }

  // A held frame nothing came after (the end of a log): ignored.
  void drop_held(ClockCounters& counters, std::string& event) {
    if (!held_) return;
    ++counters.outliers;
    event = fmt::format(
        "{} frame at utime {} is {} from its stream's time (utime {}) and the next frame did not "
        "follow it: ignored",
        stream_, held_->first, seconds(held_->first, *newest_), *newest_);
    held_.reset();
  }

  int epoch() const { return epoch_; }

 private:
  static constexpr size_t kSteps = 3;  // the steps a stream's own step is the shortest of

  // Unsigned: utimes of opposite sign and far apart (INT64_MIN) do not overflow.
  static uint64_t apart(int64_t a, int64_t b) {
    return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                 : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
  }

  // Within a jump of `from`, or ahead of it by at most 1.5 of the stream's steps.
  bool near(int64_t utime, int64_t from) const {
    const uint64_t d = apart(utime, from);
    const uint64_t step = own_step();
    return d <= static_cast<uint64_t>(jump_us_) || (utime > from && d <= step + step / 2);
  }

  // The frame after a held one: near it, or, the held one being ahead of
  // the newest, on from it by at most 1.5 times that step (a slow stream
  // whose step is not known yet).
  bool follows(int64_t utime, int64_t held) const {
    if (near(utime, held)) return true;
    if (steps_.size() >= kSteps) return false;
    const uint64_t step = std::min(apart(held, *newest_), UINT64_MAX / 4);
    return held > *newest_ && utime > held && apart(utime, held) <= step + step / 2;
  }

  // 0 until kSteps are known; at most a quarter of the range, so 1.5 steps cannot overflow.
  uint64_t own_step() const {
    if (steps_.size() < kSteps) return 0;
    return std::min(*std::min_element(steps_.begin(), steps_.end()), UINT64_MAX / 4);
  }

  // Signed seconds from `from` to `to`, cut (not rounded) to a tenth; in
  // doubles, so utimes far apart do not overflow.
  static std::string seconds(int64_t to, int64_t from) {
    const double us = static_cast<double>(to) - static_cast<double>(from);
    const std::string s = std::to_string(us / 1e6);
    return (us >= 0 ? "+" : "") + s.substr(0, s.find('.') + 2) + " s";
  }

  void take_held(ClockCounters& counters, std::string& event, std::vector<Admitted>& out) {
    auto [utime, frame] = std::move(*held_);
    held_.reset();
    if (utime < *newest_) {
      ++epoch_;
      ++counters.restarts;
      event = fmt::format(
          "{} stream's time went back {} (utime {} to {}) and stayed: a log played again? Its "
          "frames are paired with the other stream's after its own restart",
          stream_, seconds(utime, *newest_), *newest_, utime);
      newest_ = utime;
    }
    take(utime, std::move(frame), out, /*a_step=*/false);
  }

  // `a_step`: the frame came as the stream's next, not after a jump.
  void take(int64_t utime, Frame frame, std::vector<Admitted>& out, bool a_step = true) {
    if (a_step && newest_ && utime > *newest_) {
      steps_.push_back(apart(utime, *newest_));
      if (steps_.size() > kSteps) steps_.pop_front();
    }
    if (!newest_ || utime > *newest_) newest_ = utime;
    out.push_back({utime, std::move(frame), epoch_});
  }

  std::string stream_;
  int64_t jump_us_;
  int epoch_ = 0;
  std::optional<int64_t> newest_;
  std::deque<uint64_t> steps_;  // the last forward steps between frames taken as they came
  std::optional<std::pair<int64_t, Frame>> held_;
};

}  // namespace ivoa::monitor
