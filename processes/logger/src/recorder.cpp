#include "ivoa/logger/recorder.hpp"

#include <algorithm>
#include <chrono>

#include <spdlog/spdlog.h>

#include "ivoa/core/message_registry.hpp"
#include "ivoa/core/time.hpp"

namespace ivoa::logger {
namespace {

constexpr double kDropWarningIntervalMs = 2000;

std::vector<std::string> always_recorded(const RecorderOptions& options) {
  if (options.log.calibration_channel.empty()) return {};
  return {options.log.calibration_channel};
}

double mb(int64_t bytes) { return static_cast<double>(bytes) / 1e6; }

}  // namespace

Recorder::Recorder(RecorderOptions options)
    : options_(std::move(options)),
      filter_(options_.channels, options_.exclude, always_recorded(options_)),
      reserve_(options_.log.path, options_.disk_reserve),
      log_(options_.log, counters_),
      queue_(options_.max_queue_bytes) {
  writer_ = std::thread([this] { write_loop(); });
}

Recorder::~Recorder() { finish(); }

bool Recorder::on_message(const std::string& channel, int64_t timestamp, const void* data, size_t size) {
  if (!filter_.accepts(channel)) return false;
  counters_.received.fetch_add(1);
  if (channel == options_.log.calibration_channel) calibration_seen_.store(true);
  // Heartbeats are told by their type, not their channel: each process may
  // have been given its own --status-channel.
  if (first_data_ms_.load() < 0 && payload_type_name(data, size) != "ivoa.process_status_t")
    first_data_ms_.store(monotonic_ms());
  RecordedEvent event;
  event.channel = channel;
  event.timestamp = timestamp;
  const auto* bytes = static_cast<const uint8_t*>(data);
  event.data.assign(bytes, bytes + size);
  if (queue_.push(std::move(event))) return true;
  counters_.dropped.fetch_add(1);
  counters_.dropped_bytes.fetch_add(static_cast<int64_t>(size));
  return false;
}

void Recorder::write_loop() {
  RecordedEvent event;
  const double start_ms = monotonic_ms();
  while (queue_.pop(event)) {
    if (failed_.load()) continue;  // the log is closed; finish() reports these as unwritten
    try {
      reserve_.check(monotonic_ms(), static_cast<uint64_t>(counters_.bytes_written.load()),
                     event.channel.size() + event.data.size());
      log_.write(event);
      counters_.written.fetch_add(1);
    } catch (const logio::LogWriteError& e) {
      fail(e.what());
    }
    throttle(start_ms);
  }
  if (failed_.load()) return;
  try {
    log_.close();
  } catch (const logio::LogWriteError& e) {
    fail(e.what());
  }
}

void Recorder::fail(const std::string& error) {
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    error_ = error;
  }
  failed_.store(true);
  try {
    log_.close(error);
  } catch (const logio::LogWriteError& e) {
    spdlog::error("{}", e.what());
  }
}

// Keeps the average write rate under the cap by sleeping after writes, in
// short naps so that lift_write_cap() takes effect at once.
void Recorder::throttle(double start_ms) {
  if (options_.max_write_bytes_per_s <= 0) return;
  const double due_ms =
      start_ms + static_cast<double>(counters_.bytes_written.load()) / options_.max_write_bytes_per_s * 1000.0;
  constexpr double kNapMs = 50;
  for (double wait_ms = due_ms - monotonic_ms(); wait_ms > 0 && !write_cap_lifted_.load();
       wait_ms = due_ms - monotonic_ms())
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(std::min(wait_ms, kNapMs)));
}

std::string Recorder::check_health() {
  const RecorderStatus s = status();
  const double now = monotonic_ms();
  if (s.failed) return "error: " + s.error;
  if (s.dropped > dropped_reported_ && now - last_drop_warning_ms_ > kDropWarningIntervalMs) {
    spdlog::warn("the disk is not keeping up: {} messages ({:.1f} MB) dropped so far, queue full at {:.0f} MB",
                 s.dropped, mb(s.dropped_bytes), mb(static_cast<int64_t>(queue_.max_bytes())));
    dropped_reported_ = s.dropped;
    last_drop_warning_ms_ = now;
  }
  // Warn when the queue passes half full; again only after it has fallen below a quarter.
  const auto queued = static_cast<uint64_t>(s.queue_bytes);
  if (queued > queue_.max_bytes() / 2 && !queue_warned_) {
    spdlog::warn("write queue above half full ({:.0f} of {:.0f} MB): the disk is slower than the traffic",
                 mb(s.queue_bytes), mb(static_cast<int64_t>(queue_.max_bytes())));
    queue_warned_ = true;
  } else if (queued < queue_.max_bytes() / 4) {
    queue_warned_ = false;
  }
  const double first_data_ms = first_data_ms_.load();
  if (!s.calibration_seen && !options_.log.calibration_channel.empty() && !calibration_warned_ && first_data_ms >= 0 &&
      now - first_data_ms > options_.calibration_warning_s * 1000.0) {
    spdlog::warn("no {} message {:.0f} s after the first data: this log will not be self-contained until one arrives",
                 options_.log.calibration_channel, options_.calibration_warning_s);
    calibration_warned_ = true;
  }
  if (s.dropped > 0) return "recording, messages dropped (disk too slow)";
  if (!s.calibration_seen && calibration_warned_) return "recording, no " + options_.log.calibration_channel;
  return "recording";
}

bool Recorder::finish() {
  if (!finished_) {
    finished_ = true;
    lift_write_cap();
    queue_.close();
    writer_.join();
  }
  const RecorderStatus s = status();
  return !s.failed && s.unwritten == 0 && s.dropped == 0;
}

RecorderStatus Recorder::status() const {
  RecorderStatus s;
  // Written and dropped before received, so that unwritten is never negative.
  s.written = counters_.written.load();
  s.dropped = counters_.dropped.load();
  s.received = counters_.received.load();
  s.dropped_bytes = counters_.dropped_bytes.load();
  s.bytes_written = counters_.bytes_written.load();
  s.files = counters_.files.load();
  s.deleted = counters_.deleted.load();
  s.queue_depth = static_cast<int64_t>(queue_.depth());
  s.queue_bytes = static_cast<int64_t>(queue_.bytes());
  s.peak_queue_bytes = static_cast<int64_t>(queue_.peak_bytes());
  s.unwritten = s.received - s.written - s.dropped;
  s.calibration_seen = calibration_seen_.load();
  s.failed = failed_.load();
  std::lock_guard<std::mutex> lock(error_mutex_);
  s.error = error_;
  return s;
}

}  // namespace ivoa::logger
