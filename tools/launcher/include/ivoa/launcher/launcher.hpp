#pragma once
// ivoa-launch's run loop: supervises the selected commands (or runs a
// script), follows their heartbeats, shows the status table, and decides
// when to end (signal, --duration, --once/--until, or nothing left to run);
// then runs the stop script, if any, and stops what is left.
#include <map>
#include <string>
#include <vector>

#include "ivoa/launcher/config.hpp"
#include "ivoa/launcher/selection.hpp"
#include "ivoa/launcher/supervisor.hpp"
#include "ivoa/launcher/variables.hpp"

namespace ivoa::launcher {

struct LauncherOptions {
  std::string script;              // run this script instead of starting everything
  double duration_s = 0;           // > 0: stop everything after this long
  bool once = false;               // stop everything once every non-respawn command has ended
  std::vector<std::string> until;  // stop everything once these commands have ended
  double grace_s = 1.0;            // after --once/--until holds, let the others finish this long
  std::string status_file;         // written at exit: JSON if it ends in .json, else the table
  double status_every_s = 5.0;     // table period when not redrawing a terminal (0: only at the end)
  bool redraw = false;             // live table on a terminal (else lines + periodic table)
  std::string output_dir;          // also append each command's output to DIR/NAME.log
  std::string lcm_url;             // heartbeats; "none" to run without LCM
  std::string status_channel = "PROCESS_STATUS";
  // A script's wait "running" on a command that runs an ivoa program also
  // waits for its first heartbeat, at most this long (0: never waits for one).
  double ready_timeout_s = 10.0;
  // At the stop, run this script of the file first if it has one (e.g.
  // producers, then consumers, the logger last, each waited for), then
  // stop whatever still runs; "" = stop everything at once.
  std::string stop_script = "stop";
  SupervisorOptions supervisor;
};

// What the commands get in their environment so that they report where the
// launcher listens (every ivoa program takes both as its defaults, a
// command's own flags still win): IVOA_STATUS_CHANNEL = status_channel, and
// LCM_DEFAULT_URL = the URL the launcher listens on where it is a udpm://
// one (lcm_url, or if that is empty the environment's LCM_DEFAULT_URL, else
// the project's default). A memq:// or file:// URL is the launcher's alone:
// handed on, each command would talk to a queue or a file of its own.
std::map<std::string, std::string> bus_environment(const LauncherOptions& options,
                                                   const EnvironmentLookup& environment = process_environment);

// SIGINT, SIGTERM and SIGHUP stop the run cleanly; a second one kills
// every command at once. SIGPIPE is ignored.
void install_launcher_signal_handlers();

// Runs until the end condition; returns the exit code: 0, or 1 if a
// command without auto_respawn ended on its own with a failure.
int run_launcher(const Config& config, std::vector<LaunchCommand> commands, const std::string& host,
                 const LauncherOptions& options);

}  // namespace ivoa::launcher
