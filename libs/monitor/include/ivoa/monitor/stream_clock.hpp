#pragma once
// Follows one stream's utimes for FramePairer. A frame whose utime is more
// than a jump away from the stream's newest is held back until the next
// frame: if that one follows it (within a jump of it, not of the newest),
// the clock moved and both are taken, a move back counting as a restart (a
// log played again, a sensor's clock reset) that starts a new epoch; if not,
// the held frame is ignored as an outlier. One wrong utime then cannot move
// the stream's time away from every frame after it.
#include <cstdint>
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
      if (near(utime, held_->first) && !near(utime, *newest_)) take_held(counters, event, out);
      else drop_held(counters, event);
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
  // Unsigned: utimes of opposite sign and far apart (INT64_MIN) do not overflow.
  bool near(int64_t a, int64_t b) const {
    const uint64_t apart = a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                                 : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
    return apart <= static_cast<uint64_t>(jump_us_);
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
    take(utime, std::move(frame), out);
  }

  void take(int64_t utime, Frame frame, std::vector<Admitted>& out) {
    if (!newest_ || utime > *newest_) newest_ = utime;
    out.push_back({utime, std::move(frame), epoch_});
  }

  std::string stream_;
  int64_t jump_us_;
  int epoch_ = 0;
  std::optional<int64_t> newest_;
  std::optional<std::pair<int64_t, Frame>> held_;
};

}  // namespace ivoa::monitor
