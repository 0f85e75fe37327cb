#pragma once
// The logger's core, without LCM: messages come in on the receive thread
// (on_message only filters, copies and queues, so LCM is never held up by
// the disk), a writer thread writes them to a SplitLog. finish() writes out
// everything still queued before closing: a stop loses nothing received.
// If the disk cannot keep up, the queue's byte bound holds memory in check
// and refused messages are counted and reported, never silently lost.
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ivoa/logger/disk_reserve.hpp"
#include "ivoa/logger/event_queue.hpp"
#include "ivoa/logger/session_counters.hpp"
#include "ivoa/logger/split_log.hpp"
#include "ivoa/logio/channel_filter.hpp"

namespace ivoa::logger {

struct RecorderOptions {
  SplitLogOptions log;
  std::string channels = ".*";            // include regex
  std::string exclude = "LCM_SELF_TEST";  // exclude regex, empty = none; LCM_SELF_TEST is LCM's start-up probe
  uint64_t max_queue_bytes = 1024ull << 20;
  double max_write_bytes_per_s = 0;  // cap on the disk write rate, 0 = none
  DiskReserveOptions disk_reserve;   // stop short of filling the disk
  // Warn if no calibration arrived this long after the first message that is
  // not a heartbeat: the loggers of the pmd files start seconds before the
  // drivers, and the processes' heartbeats come first.
  double calibration_warning_s = 5;
};

struct RecorderStatus {
  int64_t received = 0, written = 0, dropped = 0, dropped_bytes = 0, bytes_written = 0, files = 0;
  int64_t deleted = 0;  // written, then deleted with their file while recording
  int64_t queue_depth = 0, queue_bytes = 0, peak_queue_bytes = 0;
  int64_t unwritten = 0;  // received but neither written nor dropped: queued, or lost to a write error
  bool calibration_seen = false;
  bool failed = false;
  std::string error;
};

class Recorder {
 public:
  // Opens the first file and starts the writer thread. Throws
  // logio::LogWriteError (cannot create the log, or the disk is already
  // down to its reserve) or std::invalid_argument (bad regex).
  explicit Recorder(RecorderOptions options);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Receive thread only. Returns false if the message was for a channel
  // that is not recorded, or was refused because the queue is full.
  bool on_message(const std::string& channel, int64_t timestamp, const void* data, size_t size);

  // Call now and then from the receive thread: logs warnings (disk too
  // slow, messages dropped, no calibration yet) and returns a one-line
  // state for the heartbeat.
  std::string check_health();

  // From now on writes as fast as the disk allows: the write cap spares a
  // shared disk while recording, but must not hold up a stop (at 1 kB/s a
  // 100 MB backlog would take a day).
  void lift_write_cap() { write_cap_lifted_.store(true); }

  // Takes no more messages, writes out all queued ones (the cap lifted),
  // closes the log. Returns true if every message received is on disk.
  // Idempotent.
  bool finish();

  bool failed() const { return failed_.load(); }
  RecorderStatus status() const;
  const std::vector<std::string>& files() const { return log_.files(); }

 private:
  void write_loop();
  void fail(const std::string& error);
  void throttle(double start_ms);

  RecorderOptions options_;
  logio::ChannelFilter filter_;
  SessionCounters counters_;
  DiskReserve reserve_;  // before log_: no file is created on a disk without room
  SplitLog log_;
  EventQueue queue_;
  std::atomic<bool> failed_{false};
  std::atomic<bool> calibration_seen_{false};
  std::atomic<bool> write_cap_lifted_{false};
  std::atomic<double> first_data_ms_{-1};  // the first message other than a heartbeat
  mutable std::mutex error_mutex_;
  std::string error_;
  std::thread writer_;
  bool finished_ = false;

  // check_health() state (receive thread only).
  double last_drop_warning_ms_ = -1e18;
  int64_t dropped_reported_ = 0;
  bool queue_warned_ = false;
  bool calibration_warned_ = false;
};

}  // namespace ivoa::logger
