#pragma once
// The launcher's status table (terminal, log) and its JSON form (--status-file).
#include <optional>
#include <string>
#include <vector>

#include "ivoa/launcher/supervisor.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa::launcher {

struct StatusRow {
  CommandStatus command;
  std::optional<process_status_t> heartbeat;  // newest PROCESS_STATUS of the command, if any
  double heartbeat_age_s = 0;
};

struct RunSummary {
  std::string config_path, host;
  double elapsed_s = 0;
  std::string end_reason;  // "running", "duration", "signal", "commands ended", ...
  int exit_code = 0;
};

// Columns: name, pid, state, restarts, exit, then from the heartbeat: in,
// out, dropped, bad input, mean latency (ms), its state and age.
std::string format_status_table(const std::vector<StatusRow>& rows);
std::string format_status_json(const std::vector<StatusRow>& rows, const RunSummary& summary);

// "3", "SIGKILL", "-" (never ended).
std::string describe_exit(const CommandStatus& status);

}  // namespace ivoa::launcher
