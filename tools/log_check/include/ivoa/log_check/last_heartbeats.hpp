#pragma once
// The last heartbeat (ivoa.process_status_t) each process published in a
// log: how every process of a recorded session ended (its final state and
// counts), and how many times it was started (distinct pids). A process
// that was stopped before the logger has "stopped" here; one the logger
// outlived by less shows what it said last.
#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "ivoa/logio/log_reader.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa::log_check {

struct LastHeartbeat {
  process_status_t status;  // the newest by utime
  std::set<int32_t> pids;   // every pid that process ran as
  int64_t heartbeats = 0;
};

class LastHeartbeats {
 public:
  // Events that are not heartbeats are ignored.
  void add(const logio::LogEvent& event);
  const std::map<std::string, LastHeartbeat>& processes() const { return processes_; }
  // One line per process, for people ("" when the log has no heartbeat).
  std::string table() const;
  // {"name": {"state": ..., "pid": ..., "runs": ..., ...}, ...}
  std::string json() const;

 private:
  std::map<std::string, LastHeartbeat> processes_;
};

}  // namespace ivoa::log_check
