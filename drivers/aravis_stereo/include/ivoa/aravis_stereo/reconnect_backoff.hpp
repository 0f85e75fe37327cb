#pragma once
// How long to wait before the next attempt to (re)open a camera: doubles
// after each failure up to a ceiling, back to the start after a success.
#include <algorithm>

namespace ivoa::aravis_stereo {

struct BackoffOptions {
  double initial_s = 0.5;  // wait before the first retry, seconds
  double factor = 2.0;     // each failure multiplies the wait by this
  double max_s = 8.0;      // the wait never exceeds this, seconds
};

class ReconnectBackoff {
 public:
  explicit ReconnectBackoff(const BackoffOptions& options = {}) : options_(options), next_s_(options.initial_s) {}

  // The wait before the next attempt; each call lengthens the one after.
  double next_delay_s() {
    const double delay = next_s_;
    next_s_ = std::min(options_.max_s, next_s_ * options_.factor);
    ++failures_;
    return delay;
  }
  void succeeded() {
    next_s_ = options_.initial_s;
    failures_ = 0;
  }
  int failures() const { return failures_; }

 private:
  BackoffOptions options_;
  double next_s_;
  int failures_ = 0;
};

}  // namespace ivoa::aravis_stereo
