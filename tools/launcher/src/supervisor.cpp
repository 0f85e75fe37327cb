#include "ivoa/launcher/supervisor.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <system_error>

#include "child_process.hpp"

namespace ivoa::launcher {
namespace {

// After SIGKILL, how long a group may still look alive (zombies nobody
// reaps) before the command counts as ended anyway.
constexpr double kAfterKillGraceS = 1.0;

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }
std::chrono::steady_clock::duration duration_s(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

const char* to_string(RunState state) {
  switch (state) {
    case RunState::kIdle: return "idle";
    case RunState::kRunning: return "running";
    case RunState::kStopping: return "stopping";
    case RunState::kRespawning: return "respawning";
    case RunState::kStopped: return "stopped";
  }
  return "?";
}

struct Supervisor::Instance {
  LaunchCommand command;
  CommandStatus status;
  bool leader_alive = false;
  bool start_when_ended = false;  // restart(): start again once this run has ended
  bool kill_sent = false;
  int output_fd = -1;
  std::string partial_line;
  double backoff_s = 0;
  Clock::time_point started_at, deadline, respawn_at;
};

Supervisor::Supervisor(std::vector<LaunchCommand> commands, SupervisorOptions options, OutputHandler on_output,
                       EventHandler on_event)
    : options_(std::move(options)), on_output_(std::move(on_output)), on_event_(std::move(on_event)) {
  for (auto& c : commands) {
    auto instance = std::make_unique<Instance>();
    instance->status.name = c.spec.name;
    instance->status.group = c.spec.group;
    instance->status.host = c.spec.host.empty() ? "localhost" : c.spec.host;
    instance->status.auto_respawn = c.spec.auto_respawn;
    instance->backoff_s = options_.respawn_delay_s;
    instance->command = std::move(c);
    commands_.push_back(std::move(instance));
  }
}

Supervisor::~Supervisor() {
  for (auto& c : commands_) {
    if (c->leader_alive || c->status.state == RunState::kStopping) {
      kill(-c->status.pid, SIGKILL);
      if (c->leader_alive) waitpid(c->status.pid, nullptr, 0);
    }
    if (c->output_fd >= 0) close(c->output_fd);
  }
}

Supervisor::Instance& Supervisor::find(const std::string& name) {
  for (auto& c : commands_)
    if (c->status.name == name) return *c;
  throw std::out_of_range("no command \"" + name + "\"");
}
const Supervisor::Instance& Supervisor::find(const std::string& name) const {
  return const_cast<Supervisor*>(this)->find(name);
}

void Supervisor::start(const std::string& name) {
  Instance& c = find(name);
  switch (c.status.state) {
    case RunState::kRunning: return;
    case RunState::kStopping: c.start_when_ended = true; return;
    default: spawn(c);
  }
}

void Supervisor::stop(const std::string& name) {
  Instance& c = find(name);
  c.start_when_ended = false;
  c.status.stop_requested = true;
  if (c.status.state == RunState::kRespawning) {
    c.status.state = RunState::kStopped;
    on_event_(name, "respawn cancelled");
  }
  if (c.status.state != RunState::kRunning) return;
  signal_group(c, c.command.spec.stop_signal);
  c.status.state = RunState::kStopping;
  c.deadline = Clock::now() + duration_s(c.command.spec.stop_time_allowed_s);
}

void Supervisor::restart(const std::string& name) {
  Instance& c = find(name);
  if (c.status.state == RunState::kRunning || c.status.state == RunState::kStopping) {
    stop(name);
    c.start_when_ended = true;
  } else {
    spawn(c);
  }
}

void Supervisor::start_all() {
  for (auto& c : commands_) start(c->status.name);
}
void Supervisor::stop_all() {
  for (auto& c : commands_) stop(c->status.name);
}

void Supervisor::kill_all() {
  for (auto& c : commands_) {
    c->start_when_ended = false;
    c->status.stop_requested = true;
    if (c->status.state == RunState::kRespawning) c->status.state = RunState::kStopped;
    if (c->status.state != RunState::kRunning && c->status.state != RunState::kStopping) continue;
    signal_group(*c, SIGKILL);
    c->status.state = RunState::kStopping;
    c->status.killed = c->leader_alive;
    c->kill_sent = true;
    c->deadline = Clock::now();
  }
}

void Supervisor::spawn(Instance& c) {
  const auto& spec = c.command.spec;
  if (c.status.pid > 0 || c.status.failed) ++c.status.restarts;
  c.start_when_ended = false;
  c.status.stop_requested = false;
  c.status.killed = false;
  c.started_at = Clock::now();
  ChildProcess child;
  try {
    child = spawn_shell_command(exec_form(c.command.shell_command), options_.environment, spec.stop_signal);
  } catch (const std::system_error& e) {
    // Out of processes or descriptors: a failed start, retried like a crash.
    on_event_(spec.name, std::string("cannot start: ") + e.what());
    c.status.exit_code = -1;
    c.status.exit_signal = 0;
    c.status.failed = true;
    if (spec.auto_respawn) schedule_respawn(c);
    else c.status.state = RunState::kStopped;
    return;
  }
  c.status.pid = child.pid;
  c.output_fd = child.output_fd;
  c.leader_alive = true;
  c.kill_sent = false;
  c.status.state = RunState::kRunning;
  // (A launcher killed between the fork and here leaves this group to the
  // kernel's death signal alone: microseconds.)
  if (options_.on_group_started) options_.on_group_started(child.pid, spec);
  on_event_(spec.name, "started, pid " + std::to_string(child.pid));
}

void Supervisor::signal_group(Instance& c, int signal) {
  if (kill(-c.status.pid, signal) != 0 && c.leader_alive) kill(c.status.pid, signal);
}

bool Supervisor::step(int timeout_ms, int wake_fd) {
  std::vector<pollfd> fds;
  std::vector<Instance*> owners;
  for (auto& c : commands_)
    if (c->output_fd >= 0) {
      fds.push_back({c->output_fd, POLLIN, 0});
      owners.push_back(c.get());
    }
  if (wake_fd >= 0) fds.push_back({wake_fd, POLLIN, 0});
  const int n = poll(fds.data(), fds.size(), poll_timeout_ms(timeout_ms));
  bool woken = false;
  if (n > 0) {
    for (size_t i = 0; i < owners.size(); ++i)
      if (fds[i].revents) read_output(*owners[i], false);
    woken = wake_fd >= 0 && fds.back().revents != 0;
  }
  reap();
  handle_deadlines();
  return woken;
}

int Supervisor::poll_timeout_ms(int limit_ms) const {
  double wait_s = limit_ms / 1000.0;
  const auto now = Clock::now();
  for (const auto& c : commands_) {
    if (c->status.state == RunState::kRespawning) wait_s = std::min(wait_s, seconds(c->respawn_at - now));
    if (c->status.state == RunState::kStopping) wait_s = std::min(wait_s, seconds(c->deadline - now));
    // Leaders are reaped by polling: do not sleep long while any runs.
    if (c->leader_alive || c->status.state == RunState::kStopping) wait_s = std::min(wait_s, 0.05);
  }
  return std::max(0, static_cast<int>(std::ceil(wait_s * 1000.0)));
}

void Supervisor::read_output(Instance& c, bool to_end) {
  // A bounded amount per call, so one chatty command cannot starve the others
  // (nor, at its end, keep us reading what an escaped child still writes).
  char buffer[8192];
  const int max_reads = to_end ? 1024 : 8;
  bool at_end = false;
  for (int reads = 0; reads < max_reads && !at_end; ++reads) {
    const ssize_t n = read(c.output_fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;  // nothing more for now
    at_end = n == 0;
    c.partial_line.append(buffer, static_cast<size_t>(n));
    size_t newline;
    while ((newline = c.partial_line.find('\n')) != std::string::npos) {
      on_output_(c.status.name, c.partial_line.substr(0, newline));
      c.partial_line.erase(0, newline + 1);
    }
  }
  if (!at_end && !to_end) return;
  if (!c.partial_line.empty()) on_output_(c.status.name, c.partial_line);
  c.partial_line.clear();
  close(c.output_fd);
  c.output_fd = -1;
}

void Supervisor::reap() {
  int status = 0;
  if (options_.reap_orphans) {
    pid_t pid;
    while ((pid = waitpid(-1, &status, WNOHANG)) > 0)
      for (auto& c : commands_)
        if (c->leader_alive && c->status.pid == pid) on_leader_exit(*c, status);
  } else {
    for (auto& c : commands_)
      if (c->leader_alive && waitpid(c->status.pid, &status, WNOHANG) == c->status.pid) on_leader_exit(*c, status);
  }
  for (auto& c : commands_)
    if (!c->leader_alive && c->status.state == RunState::kStopping) check_group_gone(*c);
}

void Supervisor::on_leader_exit(Instance& c, int wait_status) {
  c.leader_alive = false;
  c.status.exit_code = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
  c.status.exit_signal = WIFSIGNALED(wait_status) ? WTERMSIG(wait_status) : 0;
  c.status.failed = !c.status.stop_requested && (c.status.exit_code != 0);
  on_event_(c.status.name, std::string(c.status.stop_requested ? "stopped: " : "ended: ") +
                               describe_wait_status(wait_status) + (c.status.killed ? " (after SIGKILL)" : ""));
  if (c.status.state == RunState::kRunning) {
    // What it started in its group goes with it.
    c.status.state = RunState::kStopping;
    signal_group(c, c.command.spec.stop_signal);
    c.deadline = Clock::now() + duration_s(c.command.spec.stop_time_allowed_s);
  }
  check_group_gone(c);
}

void Supervisor::check_group_gone(Instance& c) {
  const bool gone = kill(-c.status.pid, 0) != 0 && errno == ESRCH;
  const bool given_up = c.kill_sent && Clock::now() > c.deadline + duration_s(kAfterKillGraceS);
  if (gone || given_up) finish(c);
}

void Supervisor::finish(Instance& c) {
  if (options_.on_group_gone) options_.on_group_gone(c.status.pid);
  if (c.output_fd >= 0) read_output(c, true);
  if (c.start_when_ended) {
    spawn(c);
    return;
  }
  if (c.status.stop_requested || !c.command.spec.auto_respawn) {
    c.status.state = RunState::kStopped;
    return;
  }
  schedule_respawn(c);
}

void Supervisor::schedule_respawn(Instance& c) {
  // Back-off: 1, 2, 4 ... s while it keeps failing quickly; reset after a healthy run.
  if (seconds(Clock::now() - c.started_at) >= options_.healthy_after_s) c.backoff_s = options_.respawn_delay_s;
  c.status.state = RunState::kRespawning;
  c.respawn_at = Clock::now() + duration_s(c.backoff_s);
  char text[64];
  std::snprintf(text, sizeof(text), "respawning in %.1f s", c.backoff_s);
  on_event_(c.status.name, text);
  c.backoff_s = std::min(c.backoff_s * 2, options_.respawn_max_delay_s);
}

void Supervisor::handle_deadlines() {
  const auto now = Clock::now();
  for (auto& c : commands_) {
    if (c->status.state == RunState::kRespawning && now >= c->respawn_at) {
      spawn(*c);
    } else if (c->status.state == RunState::kStopping && !c->kill_sent && now >= c->deadline) {
      char text[96];
      std::snprintf(text, sizeof(text), "still running %.1f s after the stop signal: SIGKILL",
                    c->command.spec.stop_time_allowed_s);
      on_event_(c->status.name, text);
      signal_group(*c, SIGKILL);
      c->kill_sent = true;
      c->status.killed = c->leader_alive;
    }
  }
}

bool Supervisor::busy() const {
  for (const auto& c : commands_) {
    const RunState s = c->status.state;
    if (s == RunState::kRunning || s == RunState::kStopping || s == RunState::kRespawning) return true;
  }
  return false;
}

std::vector<std::string> Supervisor::names() const {
  std::vector<std::string> out;
  for (const auto& c : commands_) out.push_back(c->status.name);
  return out;
}

bool Supervisor::has(const std::string& name) const {
  return std::any_of(commands_.begin(), commands_.end(), [&](const auto& c) { return c->status.name == name; });
}

CommandStatus Supervisor::status(const std::string& name) const {
  const Instance& c = find(name);
  CommandStatus s = c.status;
  const auto now = Clock::now();
  if (c.leader_alive) s.uptime_s = seconds(now - c.started_at);
  if (s.state == RunState::kRespawning) s.respawn_in_s = std::max(0.0, seconds(c.respawn_at - now));
  return s;
}

std::vector<CommandStatus> Supervisor::statuses() const {
  std::vector<CommandStatus> out;
  for (const auto& c : commands_) out.push_back(status(c->status.name));
  return out;
}

std::optional<std::string> Supervisor::command_with_group(int pgid) const {
  for (const auto& c : commands_)
    if (c->status.pid == pgid && c->status.state != RunState::kIdle) return c->status.name;
  return std::nullopt;
}

}  // namespace ivoa::launcher
