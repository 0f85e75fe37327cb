#pragma once
// A small JSON file next to each log (<log>.json) that says what is in it
// without reading it: who wrote it (program, version, git hash, host), the
// time span (receive times of its first and last event), every channel with its type, fingerprint and count, the
// session's totals, and the fingerprints of every ivoa type, so a log
// whose types later change can still be matched to the code that wrote it.
// Written when the file is opened (complete: false), every few seconds
// while it is written (complete: false, the counts so far) and when it is
// closed, so a crash leaves a sidecar that says so and describes what the
// file held shortly before.
#include <cstdint>
#include <string>

#include "ivoa/logger/session_counters.hpp"

namespace ivoa::logio {
class LogSummary;
}

namespace ivoa::logger {

struct LoggerIdentity {
  std::string program = "ivoa-logger";
  std::string version;
  std::string git;  // git describe of the source tree at configure time
  std::string host;
  std::string lcm_url;
  std::string channels_regex;
  std::string exclude_regex;
};

struct SidecarContent {
  const LoggerIdentity* identity = nullptr;
  std::string log_path;
  int part = 0;           // index of this file in a split session
  bool complete = false;  // closed normally
  std::string error;      // why it was closed early, if it was
  bool starts_with_calibration = false;
  uint64_t file_bytes = 0;
  const logio::LogSummary* summary = nullptr;
  const SessionCounters* counters = nullptr;
};

std::string sidecar_path(const std::string& log_path);
std::string sidecar_json(const SidecarContent& content);
// Rewrites the sidecar in place (it reuses its own blocks, so this works
// on a full disk too). Returns false, with the reason in `error`, if not.
bool write_sidecar(const SidecarContent& content, std::string& error);

}  // namespace ivoa::logger
