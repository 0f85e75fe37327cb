#pragma once
// Collects the PROCESS_STATUS heartbeats of the launched commands. A
// heartbeat from this machine belongs to the command whose process group
// holds its pid (so it works whatever the process calls itself and through
// "sh -c"); one from another machine to the command of the same name.
#include <sys/types.h>

#include <chrono>
#include <map>
#include <optional>
#include <string>

#include "ivoa/core/bus.hpp"
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
  };
  std::optional<Latest> latest(const std::string& command) const;

 private:
  void on_status(const process_status_t& status);
  std::optional<std::string> local_command(pid_t pid);

  Bus& bus_;
  const Supervisor& supervisor_;
  std::string hostname_;
  std::map<std::string, Latest> latest_;
  std::map<pid_t, std::string> commands_by_pid_;  // every local pid heard from, for heartbeats read after it ended
};

}  // namespace ivoa::launcher
