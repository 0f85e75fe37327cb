#pragma once
// The launcher's status table (terminal, log) and its JSON form (--status-file).
#include <optional>
#include <string>
#include <vector>

#include "ivoa/launcher/supervisor.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa::launcher {

// The counts of a command's earlier instances (it was respawned), each by
// its last heartbeat, summed.
struct InstanceCounts {
  int64_t instances = 0, messages_in = 0, messages_out = 0, dropped = 0, bad_input = 0;
};

struct StatusRow {
  CommandStatus command;
  std::optional<process_status_t> heartbeat;  // newest PROCESS_STATUS of the command, if any
  double heartbeat_age_s = 0;
  // The instance that sent it has ended since (killed, or ended on its own)
  // and its state is not its last word: the table says so.
  bool heartbeat_sender_ended = false;
  InstanceCounts earlier;
};

struct RunSummary {
  std::string config_path, host;
  double elapsed_s = 0;
  std::string end_reason;  // "running", "duration", "signal", "commands ended", ...
  int exit_code = 0;
};

// Columns: name, pid, state, restarts, exit, then from the heartbeats: in,
// out, dropped and bad input of every instance of the command (a respawned
// one's too), then the newest's mean latency (ms), its state and age.
std::string format_status_table(const std::vector<StatusRow>& rows);
std::string format_status_json(const std::vector<StatusRow>& rows, const RunSummary& summary);

// "3", "SIGKILL", "-" (never ended).
std::string describe_exit(const CommandStatus& status);

}  // namespace ivoa::launcher
