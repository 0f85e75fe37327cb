#include "readiness_gate.hpp"

#include <cstdio>
#include <filesystem>
#include <set>

namespace ivoa::launcher {

namespace {

// The programs that send PROCESS_STATUS heartbeats: the drivers, the
// processes and the log player. The offline tools, ivoa-lcm-stats and the
// simulated camera send none.
const std::set<std::string> kAnnouncingPrograms{"ivoa-aravis-stereo",   "ivoa-openni2-kinect", "ivoa-sim-driver",
                                                "ivoa-stereo-detector", "ivoa-depth-monitor",  "ivoa-introspection",
                                                "ivoa-logger",          "ivoa-viewer",         "ivoa-log-play"};

// A word that leaves the next one in command position: `exec` or VAR=value.
bool keeps_command_position(const std::string& word) {
  const size_t eq = word.find('=');
  return word == "exec" || (eq != std::string::npos && eq > 0 && word.find('/') > eq);
}

}  // namespace

bool runs_announcing_program(const std::string& shell_command) {
  static const std::string separators = ";&|()\n", blanks = " \t", quotes = "'\"";
  bool command_position = true;
  std::string word;
  const auto end_word = [&] {
    if (word.empty()) return false;
    const bool program = command_position && !keeps_command_position(word);
    if (program && kAnnouncingPrograms.count(std::filesystem::path(word).filename().string())) return true;
    if (program) command_position = false;
    word.clear();
    return false;
  };
  for (const char c : shell_command) {
    if (quotes.find(c) != std::string::npos) continue;
    if (separators.find(c) == std::string::npos && blanks.find(c) == std::string::npos) {
      word += c;
      continue;
    }
    if (end_word()) return true;
    if (separators.find(c) != std::string::npos) command_position = true;
  }
  return end_word();
}

ReadinessGate::ReadinessGate(const std::vector<LaunchCommand>& commands, double timeout_s, EventHandler on_event)
    : timeout_s_(timeout_s), on_event_(std::move(on_event)) {
  for (const auto& c : commands)
    if (runs_announcing_program(c.shell_command)) announcing_.insert(c.spec.name);
}

bool ReadinessGate::ready(const CommandStatus& status, const std::optional<HeartbeatMonitor::Latest>& heartbeat,
                          std::chrono::steady_clock::time_point now) {
  if (timeout_s_ <= 0 || status.state != RunState::kRunning || !announcing_.count(status.name)) return true;
  const double since_heartbeat_s = heartbeat ? std::chrono::duration<double>(now - heartbeat->received).count() : -1;
  if (heartbeat && since_heartbeat_s <= status.uptime_s) return true;  // heard during this run
  if (status.uptime_s < timeout_s_) return false;
  if (gave_up_.insert({status.name, status.pid}).second) {
    char text[160];
    std::snprintf(text, sizeof(text), "no heartbeat within %.3g s of starting; the script goes on without it",
                  timeout_s_);
    on_event_(status.name, text);
  }
  return true;
}

}  // namespace ivoa::launcher
