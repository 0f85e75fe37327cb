#pragma once
// Writes LCM log files that stay readable whatever happens to the disk.
// lcm::LogFile writes through stdio, so after a failed write nobody knows
// which events reached the file; this writer issues one write per event
// and, if the disk refuses one (full, over a size limit, I/O error), cuts
// the file back to the end of the last whole event before reporting.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ivoa::logio {

// what() names the file and the system's reason.
class LogWriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LogWriterOptions {
  // Otherwise an existing file is an error. Either way a file another
  // LogWriter is writing (in any process) is refused and left as it is.
  bool overwrite = false;
  // Written data is pushed to the disk and dropped from the page cache in
  // chunks of this size, so hours of images neither pile up as dirty memory
  // nor evict everything else cached; 0 leaves it all to the kernel.
  uint64_t writeback_chunk_bytes = 32ull << 20;
};

class LogWriter {
 public:
  explicit LogWriter(std::string path, LogWriterOptions options = {});  // throws LogWriteError
  ~LogWriter();                                                         // closes quietly if close() was not called
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  // Appends one event (event numbers count from 0, as lcm-logger's do).
  // Throws LogWriteError if it could not be written whole; the file then
  // ends with the previous event and takes no more writes.
  void write(std::string_view channel, int64_t timestamp, const void* data, size_t size);
  // Syncs to the disk and closes; throws LogWriteError if that fails.
  void close();

  const std::string& path() const { return path_; }
  int64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }  // of whole events
  bool is_open() const { return fd_ >= 0; }
  // The open file has no name on disk any more (deleted while written):
  // what it holds goes when it is closed.
  bool deleted() const;

 private:
  void hold_for_writing();
  [[noreturn]] void fail(const std::string& what, int error);
  void write_back(uint64_t upto);

  std::string path_;
  LogWriterOptions options_;
  int fd_ = -1;
  bool failed_ = false;
  int64_t events_ = 0;
  uint64_t bytes_ = 0;
  uint64_t written_back_ = 0;  // bytes whose write-out has been started
  uint64_t dropped_ = 0;       // bytes known on disk and dropped from the cache
};

}  // namespace ivoa::logio
