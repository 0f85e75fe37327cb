#include "ivoa/core/heartbeat.hpp"

#include <unistd.h>

#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa {
namespace {

// At most one bad-input warning per interval; the rest are counted.
constexpr double kWarningIntervalMs = 1000.0;

std::string hostname() {
  char buf[256] = {0};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

}  // namespace

Heartbeat::Heartbeat(Bus& bus, std::string process_name, std::string channel, double period_s)
    : bus_(bus),
      channel_(std::move(channel)),
      period_ms_(period_s * 1000.0),
      name_(std::move(process_name)),
      host_(hostname()),
      pid_(static_cast<int>(getpid())),
      start_utime_(now_utime()) {}

void Heartbeat::count_in(int64_t n) {
  std::lock_guard<std::mutex> l(mutex_);
  in_ += n;
}
void Heartbeat::count_out(int64_t n) {
  std::lock_guard<std::mutex> l(mutex_);
  out_ += n;
}
void Heartbeat::count_dropped(int64_t n) {
  std::lock_guard<std::mutex> l(mutex_);
  dropped_ += n;
}

void Heartbeat::bad_input(const std::string& full_text) {
  const std::string what = full_text.size() <= kMaxErrorChars
                               ? full_text
                               : full_text.substr(0, kMaxErrorChars) + "... (" +
                                     std::to_string(full_text.size() - kMaxErrorChars) + " more characters)";
  std::lock_guard<std::mutex> l(mutex_);
  ++bad_;
  last_error_ = what;
  const double now = monotonic_ms();
  if (now - last_warning_ms_ < kWarningIntervalMs) {
    ++suppressed_warnings_;
    return;
  }
  // The ones held back were of any kind, not necessarily this one's.
  if (suppressed_warnings_ > 0)
    spdlog::warn("bad input (skipped): {} [and {} more since the last warning, counted, not shown]", what,
                 suppressed_warnings_);
  else spdlog::warn("bad input (skipped): {}", what);
  suppressed_warnings_ = 0;
  last_warning_ms_ = now;
}

void Heartbeat::latency(double ms) {
  std::lock_guard<std::mutex> l(mutex_);
  latency_sum_ += ms;
  latency_max_ = std::max(latency_max_, ms);
  ++latency_count_;
}

void Heartbeat::set_state(const std::string& state) {
  std::lock_guard<std::mutex> l(mutex_);
  if (state != state_) spdlog::info("state: {}", state);
  state_ = state;
}

void Heartbeat::set_counter(const std::string& name, int64_t value) {
  std::lock_guard<std::mutex> l(mutex_);
  counters_[name] = value;
}

void Heartbeat::add_to_counter(const std::string& name, int64_t delta) {
  std::lock_guard<std::mutex> l(mutex_);
  counters_[name] += delta;
}

process_status_t Heartbeat::make_status_locked() const {
  process_status_t msg;
  msg.utime = now_utime();
  msg.name = name_;
  msg.host = host_;
  msg.pid = pid_;
  msg.start_utime = start_utime_;
  msg.messages_in = in_;
  msg.messages_out = out_;
  msg.dropped = dropped_;
  msg.bad_input = bad_;
  msg.latency_ms_mean = latency_count_ > 0 ? latency_sum_ / static_cast<double>(latency_count_) : 0.0;
  msg.latency_ms_max = latency_max_;
  msg.state = state_;
  msg.last_error = last_error_;
  for (const auto& [name, value] : counters_) {
    msg.counter_names.push_back(name);
    msg.counter_values.push_back(value);
  }
  return msg;
}

process_status_t Heartbeat::snapshot() const {
  std::lock_guard<std::mutex> l(mutex_);
  return make_status_locked();
}

int64_t Heartbeat::bad_input_count() const {
  std::lock_guard<std::mutex> l(mutex_);
  return bad_;
}

std::string Heartbeat::summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string out = "in " + std::to_string(in_) + ", out " + std::to_string(out_) + ", dropped " +
                    std::to_string(dropped_) + ", bad " + std::to_string(bad_);
  for (const auto& [name, value] : counters_)
    if (value != 0) out += ", " + name + " " + std::to_string(value);
  return out;
}

std::optional<int64_t> Heartbeat::counter(const std::string& name) const {
  std::lock_guard<std::mutex> l(mutex_);
  const auto it = counters_.find(name);
  if (it == counters_.end()) return std::nullopt;
  return it->second;
}

void Heartbeat::tick() {
  {
    std::lock_guard<std::mutex> l(mutex_);
    if (monotonic_ms() - last_publish_ms_ < period_ms_) return;
  }
  publish_now();
}

void Heartbeat::publish_now() {
  process_status_t msg;
  {
    std::lock_guard<std::mutex> l(mutex_);
    msg = make_status_locked();
    last_publish_ms_ = monotonic_ms();
    // Latency statistics cover one heartbeat period.
    latency_sum_ = latency_max_ = 0;
    latency_count_ = 0;
  }
  bus_.publish(channel_, msg);
}

}  // namespace ivoa
