#pragma once
// One recording session on disk: a log file, or with a split size a
// numbered series (NAME.00, NAME.01, ..., as lcm-logger -i names them),
// each with its sidecar. A new file starts with a copy of the newest rig
// calibration written so far, so every file can be used on its own.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ivoa/core/channels.hpp"
#include "ivoa/logger/event_queue.hpp"
#include "ivoa/logger/session_counters.hpp"
#include "ivoa/logger/sidecar.hpp"
#include "ivoa/logio/log_summary.hpp"
#include "ivoa/logio/log_writer.hpp"

namespace ivoa::logger {

struct SplitLogOptions {
  std::string path;          // the log's name, or the stem of the numbered series
  uint64_t split_bytes = 0;  // start a new file before one would grow past this; 0 = never
  std::string calibration_channel{channels::kRigCalibration};  // copied into every new file; empty = none
  bool overwrite = false;
  bool sidecars = true;
  // While a file is written its sidecar is rewritten this often ("complete":
  // false, the counts so far), so a logger killed outright leaves one that
  // describes what the file holds. 0: after every event.
  double sidecar_refresh_s = 5;
  LoggerIdentity identity;
};

class SplitLog {
 public:
  // Opens the first file. Throws logio::LogWriteError.
  SplitLog(SplitLogOptions options, SessionCounters& counters);
  ~SplitLog();

  // Writes one event, starting the next file first if this one is full.
  // Throws logio::LogWriteError; the current file then ends with its last
  // whole event and its sidecar records the error.
  void write(const RecordedEvent& event);
  // Syncs and closes the current file; `error` says why if it ends early.
  // Throws logio::LogWriteError if the file cannot be synced.
  void close(const std::string& error = "");

  const std::vector<std::string>& files() const { return files_; }

  // The name of file `part` (0, 1, ...) of a log with these options.
  static std::string part_path(const SplitLogOptions& options, int part);

 private:
  void open_part(int part, int64_t timestamp);
  void replace_if_deleted(int64_t timestamp);
  void write_to_current(const std::string& channel, int64_t timestamp, const std::vector<uint8_t>& data);
  void update_sidecar(bool complete, const std::string& error);

  SplitLogOptions options_;
  SessionCounters& counters_;
  std::unique_ptr<logio::LogWriter> writer_;
  logio::LogSummary summary_;  // of the current file
  std::vector<std::string> files_;
  uint64_t opening_bytes_ = 0;  // what the file held before its first new event
  int64_t opening_events_ = 0;  // ... in events (the calibration copy)
  double sidecar_written_ms_ = 0;
  bool starts_with_calibration_ = false;
  std::optional<RecordedEvent> calibration_;  // the newest one written
};

}  // namespace ivoa::logger
