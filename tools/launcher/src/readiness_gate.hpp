#pragma once
// When a script's `wait "running"` holds for a command. For procman a
// command runs once its process exists, but a process that exists is not
// yet listening: a source started right after it (a log player, the
// simulator) publishes its first frames into the void. Every ivoa driver
// and process announces itself on PROCESS_STATUS once it has subscribed, so
// for a command that runs one the wait also needs that command's first
// heartbeat of its current run, or timeout_s of running without one; then
// the gate says so once and lets the script go on.
#include <chrono>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "heartbeat_monitor.hpp"
#include "ivoa/launcher/supervisor.hpp"

namespace ivoa::launcher {

// Whether a command line runs an ivoa program that sends heartbeats: a
// program (the first word of a command, after `exec` and VAR=value) whose
// file name is one of the drivers', the processes' or ivoa-log-play's.
bool runs_announcing_program(const std::string& shell_command);

class ReadinessGate {
 public:
  ReadinessGate(const std::vector<LaunchCommand>& commands, double timeout_s, EventHandler on_event);

  // `heartbeat`: the command's latest, if any. A command that is not
  // running (ended, respawning) does not hold a script up here.
  bool ready(const CommandStatus& status, const std::optional<HeartbeatMonitor::Latest>& heartbeat,
             std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now());

 private:
  std::set<std::string> announcing_;
  double timeout_s_;
  EventHandler on_event_;
  std::set<std::pair<std::string, int>> gave_up_;  // (command, pid) already reported
};

}  // namespace ivoa::launcher
