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

std::optional<HeartbeatMonitor::Sender> HeartbeatMonitor::local_sender(pid_t pid) {
  const pid_t group = getpgid(pid);
  if (group > 0) {
    auto command = supervisor_.command_with_group(group);
    if (!command) return std::nullopt;
    return senders_by_pid_[pid] = Sender{*command, group};
  }
  // The process has ended and been reaped: its last heartbeat (sent as it
  // stopped) is often read only now. Its pid is free, so no live process
  // can be mistaken for it.
  const auto known = senders_by_pid_.find(pid);
  if (known != senders_by_pid_.end()) return known->second;
  if (auto command = supervisor_.command_with_group(pid))  // a group leader never heard while alive
    return Sender{*command, pid};
  return std::nullopt;
}

void HeartbeatMonitor::on_status(const process_status_t& status) {
  Latest next;
  next.status = status;
  next.received = std::chrono::steady_clock::now();
  std::string command;
  if (status.host == hostname_) {
    const std::optional<Sender> sender = local_sender(status.pid);
    if (!sender) return;
    command = sender->command;
    next.local = true;
    next.instance = sender->group;
  } else if (supervisor_.has(status.name)) {
    command = status.name;
    next.instance = static_cast<int>(status.pid);
  } else {
    return;
  }
  CommandHeartbeats& heard = heard_[command];
  const InstanceKey key{status.host, next.instance, status.start_utime};
  const bool first = heard.last_of_instance.empty();
  heard.last_of_instance[key] = status;
  if (!first && is_a_replaced_instance(command, next, heard)) return;
  // A heartbeat's latency covers its own period; one with no work in it
  // (a process idle or stopping) keeps the last latency its instance measured.
  if (status.latency_ms_max == 0 && !first && key == heard.latest_key) {
    next.status.latency_ms_mean = heard.latest.status.latency_ms_mean;
    next.status.latency_ms_max = heard.latest.status.latency_ms_max;
  }
  heard.latest = next;
  heard.latest_key = key;
}

// A heartbeat of a local instance the command has replaced (killed and
// respawned), read after the current one's: its counts are kept, but the
// command's state is the current instance's. Which instance is current is
// the supervisor's word, not the senders' clocks (a clock stepped back, or
// another host's). Elsewhere the last heartbeat read is the state.
bool HeartbeatMonitor::is_a_replaced_instance(const std::string& command, const Latest& next,
                                              const CommandHeartbeats& heard) const {
  if (!next.local) return false;
  const int current = supervisor_.status(command).pid;
  return next.instance != current && heard.latest.local && heard.latest.instance == current;
}

std::optional<HeartbeatMonitor::Latest> HeartbeatMonitor::latest(const std::string& command) const {
  const auto it = heard_.find(command);
  if (it == heard_.end()) return std::nullopt;
  Latest latest = it->second.latest;
  for (const auto& [instance, status] : it->second.last_of_instance) {
    if (instance == it->second.latest_key) continue;
    ++latest.earlier.instances;
    latest.earlier.messages_in += status.messages_in;
    latest.earlier.messages_out += status.messages_out;
    latest.earlier.dropped += status.dropped;
    latest.earlier.bad_input += status.bad_input;
  }
  return latest;
}

}  // namespace ivoa::launcher
