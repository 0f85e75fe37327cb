#pragma once
// Runs a set of commands on this machine and keeps them running: each in
// its own process group (a command is its group: stopping it signals the
// whole group), output read line by line, auto_respawn commands restarted
// with exponential back-off, stops escalated to SIGKILL after the
// command's stop_time_allowed. Single-threaded: call step() in a loop.
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ivoa/launcher/config.hpp"

namespace ivoa::launcher {

enum class RunState {
  kIdle,  // never started
  kRunning,
  kStopping,    // stop signal sent (or what was left of its group is being stopped)
  kRespawning,  // ended; waiting for its back-off before starting again
  kStopped,     // ended, will not start again unless asked
};
const char* to_string(RunState state);

struct LaunchCommand {
  CommandSpec spec;
  std::string shell_command;  // exec with its variables expanded
};

struct CommandStatus {
  std::string name, group, host;
  bool auto_respawn = false;
  RunState state = RunState::kIdle;
  int pid = 0;                  // current (or last) process, also its process group
  int restarts = 0;             // starts after the first
  int exit_code = -1;           // of the last run; -1 if none yet or it died of a signal
  int exit_signal = 0;          // signal that ended the last run, 0 if none
  bool stop_requested = false;  // the last end was asked for (stop, restart, shutdown)
  bool killed = false;          // a stop needed SIGKILL after stop_time_allowed
  bool failed = false;          // the last run ended on its own with a non-zero code or a signal
  double uptime_s = 0;          // of the current run
  double respawn_in_s = 0;      // kRespawning: time left before the next start
};

struct SupervisorOptions {
  double respawn_delay_s = 1.0;  // first back-off; doubles on each quick failure
  double respawn_max_delay_s = 30.0;
  double healthy_after_s = 60.0;                   // a run at least this long resets the back-off
  std::map<std::string, std::string> environment;  // added to every command's environment
  bool reap_orphans = false;                       // also reap any child (set when this process is a child subreaper)
  // Told of each command's process group once it has started and once it
  // has gone (ivoa-launch hands them to its GroupWatchdog).
  std::function<void(int pgid, const CommandSpec& spec)> on_group_started;
  std::function<void(int pgid)> on_group_gone;
};

// A line a command wrote (without its newline), and launcher events about it.
using OutputHandler = std::function<void(const std::string& command, const std::string& line)>;
using EventHandler = std::function<void(const std::string& command, const std::string& event)>;

class Supervisor {
 public:
  Supervisor(std::vector<LaunchCommand> commands, SupervisorOptions options, OutputHandler on_output,
             EventHandler on_event);
  ~Supervisor();  // kills (SIGKILL) whatever still runs; stop_all() + step() is the clean way
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  // No effect on a command already running; throws std::out_of_range for an unknown name.
  void start(const std::string& name);
  void stop(const std::string& name);
  void restart(const std::string& name);
  void start_all();
  void stop_all();
  // SIGKILL to every command now (a second Ctrl-C).
  void kill_all();

  // Waits up to timeout_ms for output or for `wake_fd` (if >= 0), then
  // reaps ended commands, respawns those due and escalates overdue stops.
  // Returns true if wake_fd became readable.
  bool step(int timeout_ms, int wake_fd = -1);

  // Anything running, stopping or waiting to respawn.
  bool busy() const;
  std::vector<std::string> names() const;
  bool has(const std::string& name) const;
  CommandStatus status(const std::string& name) const;
  std::vector<CommandStatus> statuses() const;
  // The command whose process group is `pgid`, if any.
  std::optional<std::string> command_with_group(int pgid) const;

 private:
  struct Instance;
  using Clock = std::chrono::steady_clock;

  Instance& find(const std::string& name);
  const Instance& find(const std::string& name) const;
  void spawn(Instance& c);
  void schedule_respawn(Instance& c);
  void signal_group(Instance& c, int signal);
  void read_output(Instance& c, bool to_end);
  void reap();
  void on_leader_exit(Instance& c, int wait_status);
  void check_group_gone(Instance& c);
  void finish(Instance& c);
  void handle_deadlines();
  int poll_timeout_ms(int limit_ms) const;

  std::vector<std::unique_ptr<Instance>> commands_;
  SupervisorOptions options_;
  OutputHandler on_output_;
  EventHandler on_event_;
};

}  // namespace ivoa::launcher
