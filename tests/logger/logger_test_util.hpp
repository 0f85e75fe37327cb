#pragma once
// Shared pieces of the logger unit tests: payloads, reading a log back,
// and a temporary file-size limit that makes writes fail like a full disk.
#include <sys/resource.h>

#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

#include "ivoa/logio/log_reader.hpp"

namespace ivoa::test {

inline std::vector<uint8_t> numbered_bytes(size_t size, uint8_t seed) {
  std::vector<uint8_t> bytes(size);
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<uint8_t>(seed + i * 7);
  return bytes;
}

// Every good event of a log, and the reader's problems.
struct ReadBack {
  std::vector<logio::LogEvent> events;
  std::vector<logio::LogProblem> problems;
};

inline ReadBack read_back(const std::string& path, bool resync = false) {
  ReadBack r;
  logio::LogReader reader(path, {resync});
  logio::LogEvent e;
  while (reader.next(e)) r.events.push_back(e);
  r.problems = reader.problems();
  return r;
}

// Writes past `bytes` fail with EFBIG (SIGXFSZ ignored) until destroyed:
// the same short writes and errors a full disk gives, without mounting one.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    rlimit limit = old_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

}  // namespace ivoa::test
