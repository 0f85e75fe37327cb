#pragma once
// Collects the PROCESS_STATUS heartbeats of the launched commands. A
// heartbeat from this machine belongs to the command whose process group
// holds its pid (so it works whatever the process calls itself and through
// "sh -c"); one from another machine to the command of the same name.
// A respawned command is a new instance (a new process group here, a new
// pid there, and a new start time either way, so a reused pid is not taken
// for the instance before); the counts of its earlier instances, as their
// last heartbeats gave them, are kept beside the newest, so a run's totals
// are not lost with the process that was killed. A killed local instance's
// last heartbeat, read after its successor's, only adds to the counts.
#include <sys/types.h>

#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <tuple>

#include "ivoa/core/bus.hpp"
#include "ivoa/launcher/status_report.hpp"
#include "ivoa/launcher/supervisor.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa::launcher {

class HeartbeatMonitor {
 public:
  HeartbeatMonitor(Bus& bus, const std::string& channel, const Supervisor& supervisor);

  int fd() { return bus_.lcm().getFileno(); }
  // Handles every message waiting on the bus, without blocking.
  void drain();

  struct Latest {
    process_status_t status;
    std::chrono::steady_clock::time_point received;
    bool local = false;      // sent from this machine: `instance` is its process group
    int instance = 0;        // the process group here, the pid on another machine
    InstanceCounts earlier;  // the command's other instances, by the last heartbeat of each
  };
  std::optional<Latest> latest(const std::string& command) const;

 private:
  struct Sender {
    std::string command;
    pid_t group = 0;
  };
  struct InstanceKey {
    std::string host;
    int id = 0;  // Latest::instance
    int64_t start_utime = 0;
    bool operator<(const InstanceKey& o) const {
      return std::tie(host, id, start_utime) < std::tie(o.host, o.id, o.start_utime);
    }
    bool operator==(const InstanceKey& o) const { return !(*this < o) && !(o < *this); }
  };
  struct CommandHeartbeats {
    Latest latest;
    InstanceKey latest_key;
    std::map<InstanceKey, process_status_t> last_of_instance;
  };
  void on_status(const process_status_t& status);
  bool is_a_replaced_instance(const std::string& command, const Latest& next, const CommandHeartbeats& heard) const;
  std::optional<Sender> local_sender(pid_t pid);

  Bus& bus_;
  const Supervisor& supervisor_;
  std::string hostname_;
  std::map<std::string, CommandHeartbeats> heard_;
  std::map<pid_t, Sender> senders_by_pid_;  // every local pid heard from, for heartbeats read after it ended
};

}  // namespace ivoa::launcher
