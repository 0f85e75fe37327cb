#pragma once
// The PROCESS_STATUS heartbeat every process publishes once a second, with
// the counters the launcher and lcm-spy show: messages in and out, inputs
// dropped for a newer one, bad inputs, latency, and process-specific counts.
// Bad input is reported here: it is logged (rate-limited), counted, and
// kept as last_error; the process skips it and goes on. The text is cut to
// kMaxErrorChars, for it may quote the input (a 3 MB detector name made every
// heartbeat 3 MB).
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "ivoa/core/channels.hpp"

namespace ivoa {
class Bus;
class process_status_t;

// Counter of inputs skipped because no RIG_CALIBRATION has arrived yet. Not
// bad input: a consumer started a moment before the driver sees a frame or
// two first, and the state says "waiting for calibration" meanwhile.
inline constexpr const char* kFramesWithoutCalibration = "frames_without_calibration";

inline constexpr size_t kMaxErrorChars = 1000;

class Heartbeat {
 public:
  Heartbeat(Bus& bus, std::string process_name, std::string channel = std::string(channels::kProcessStatus),
            double period_s = 1.0);

  void count_in(int64_t n = 1);
  void count_out(int64_t n = 1);
  void count_dropped(int64_t n = 1);
  void bad_input(const std::string& what);
  void latency(double ms);
  void set_state(const std::string& state);
  void set_counter(const std::string& name, int64_t value);
  void add_to_counter(const std::string& name, int64_t delta);

  // Publishes if a period has passed since the last heartbeat. Thread-safe.
  void tick();
  // Publishes now (e.g. a final status on shutdown).
  void publish_now();

  process_status_t snapshot() const;
  int64_t bad_input_count() const;
  // A process-specific counter's value; nullopt if it was never set.
  std::optional<int64_t> counter(const std::string& name) const;
  // "in 96, out 96, dropped 0, bad 0" and the counters that are not 0, for
  // the line a process logs as it exits.
  std::string summary() const;

 private:
  process_status_t make_status_locked() const;

  Bus& bus_;
  std::string channel_;
  double period_ms_;
  mutable std::mutex mutex_;
  std::string name_, host_, state_ = "starting", last_error_;
  int pid_;
  int64_t start_utime_;
  int64_t in_ = 0, out_ = 0, dropped_ = 0, bad_ = 0;
  double latency_sum_ = 0, latency_max_ = 0;
  int64_t latency_count_ = 0;
  std::map<std::string, int64_t> counters_;
  double last_publish_ms_ = -1e18;
  double last_warning_ms_ = -1e18;
  int64_t suppressed_warnings_ = 0;
};

}  // namespace ivoa
