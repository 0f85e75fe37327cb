#pragma once
// Shared pieces of the logger unit tests: payloads, reading a log back, and
// (file_size_limit.hpp) a temporary file-size limit that makes writes fail
// like a full disk.
#include <cstdint>
#include <string>
#include <vector>

#include "file_size_limit.hpp"
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

}  // namespace ivoa::test
