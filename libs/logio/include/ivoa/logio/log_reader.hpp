#pragma once
// Reads LCM log files event by event and says exactly where one goes bad.
// lcm::LogFile (1.3.1) just returns NULL at a damaged event, which looks
// like a clean end of file; this reader records what is wrong and at which
// byte offset, after returning every good event before it, and can skip
// ahead to the next good event instead of stopping.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "ivoa/core/message_decode.hpp"

namespace ivoa::logio {
struct EventHeader;

struct LogEvent {
  uint64_t offset = 0;  // byte offset of the event in its file
  int64_t event_number = 0;
  int64_t timestamp = 0;  // microseconds since the epoch, the logger's receive time
  std::string channel;
  std::vector<uint8_t> data;  // the encoded message, fingerprint first
};

// Decodes an event's message as an lcm-gen type; false if it is not one
// (another fingerprint, truncated, or damaged inside).
template <class Msg>
bool decode(const LogEvent& event, Msg& msg) {
  return decode_message(msg, event.data.data(), event.data.size());
}

struct LogProblem {
  uint64_t offset = 0;  // where the bad event (or the garbage) starts
  std::string what;
  uint64_t skipped_bytes = 0;    // bytes skipped to the next good event, or to the end of the file
  bool to_end = false;           // no good event follows: reading stopped here
  bool cut_short = false;        // the file ends inside this event, as when a recording stops mid-write
  std::string describe() const;  // "byte 123: what (N bytes skipped ...)"
};

// The file cannot be opened or read at all (missing, permissions, I/O error).
class LogReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LogReaderOptions {
  // After a bad event, look for the next plausible event and go on
  // (reporting the skipped bytes) instead of stopping there.
  bool resync = false;
  // Leave each event's data unread (LogEvent::data empty): channels and
  // times only, without reading the images.
  bool headers_only = false;
};

class LogReader {
 public:
  explicit LogReader(std::string path, LogReaderOptions options = {});  // throws LogReadError
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  // Reads the next good event into `event` (its buffers are reused).
  // Returns false at the end of the file or where reading had to stop.
  bool next(LogEvent& event);

  const std::vector<LogProblem>& problems() const { return problems_; }
  bool clean() const { return problems_.empty(); }
  // After reading: "not an LCM log, or damaged from its start (byte 0: …)"
  // if no event could be read from its first byte, else "". Tools say this
  // instead of what the log lacks.
  std::string not_a_log() const;
  const std::string& path() const { return path_; }
  uint64_t size() const { return size_; }          // the file's size when opened
  uint64_t position() const { return position_; }  // bytes read or skipped so far

 private:
  // Empty if a plausible event starts at `offset` (its header and channel
  // are then in `header` and `channel`), else what is wrong with it;
  // `cut_short` says whether the file merely ends inside that event.
  std::string check_event_at(uint64_t offset, EventHeader& header, std::string& channel, bool& cut_short);
  void read_exactly(void* out, size_t bytes, uint64_t offset);
  bool recover(uint64_t offset, std::string what, bool cut_short);
  uint64_t find_next_event(uint64_t from);

  std::string path_;
  LogReaderOptions options_;
  int fd_ = -1;
  uint64_t size_ = 0;
  uint64_t position_ = 0;
  bool stopped_ = false;
  std::vector<LogProblem> problems_;
};

}  // namespace ivoa::logio
