#include "heartbeat_monitor.hpp"

#include <unistd.h>

namespace ivoa::launcher {

HeartbeatMonitor::HeartbeatMonitor(Bus& bus, const std::string& channel, const Supervisor& supervisor)
    : bus_(bus), supervisor_(supervisor) {
  char name[256] = {0};
  gethostname(name, sizeof(name) - 1);
  hostname_ = name;
  bus_.subscribe<process_status_t>(channel, [this](const process_status_t& s, const ReceiveInfo&) { on_status(s); });
}

void HeartbeatMonitor::drain() {
  while (bus_.handle(0) > 0) {
  }
}

std::optional<std::string> HeartbeatMonitor::local_command(pid_t pid) {
  const pid_t group = getpgid(pid);
  if (group > 0) {
    auto command = supervisor_.command_with_group(group);
    if (command) commands_by_pid_[pid] = *command;
    return command;
  }
  // The process has ended and been reaped: its last heartbeat (sent as it
  // stopped) is often read only now. Its pid is free, so no live process
  // can be mistaken for it.
  const auto known = commands_by_pid_.find(pid);
  if (known != commands_by_pid_.end()) return known->second;
  return supervisor_.command_with_group(pid);  // a group leader never heard while alive
}

void HeartbeatMonitor::on_status(const process_status_t& status) {
  std::optional<std::string> command;
  if (status.host == hostname_) command = local_command(status.pid);
  else if (supervisor_.has(status.name)) command = status.name;
  if (!command) return;
  Latest next{status, std::chrono::steady_clock::now()};
  // A heartbeat's latency covers its own period; one with no work in it
  // (a process idle or stopping) keeps the last latency measured.
  const auto previous = latest_.find(*command);
  if (status.latency_ms_max == 0 && previous != latest_.end()) {
    next.status.latency_ms_mean = previous->second.status.latency_ms_mean;
    next.status.latency_ms_max = previous->second.status.latency_ms_max;
  }
  latest_[*command] = next;
}

std::optional<HeartbeatMonitor::Latest> HeartbeatMonitor::latest(const std::string& command) const {
  const auto it = latest_.find(command);
  if (it == latest_.end()) return std::nullopt;
  return it->second;
}

}  // namespace ivoa::launcher
