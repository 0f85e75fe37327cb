#include "child_process.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <set>
#include <system_error>
#include <vector>

extern char** environ;

namespace ivoa::launcher {
namespace {

std::vector<std::string> merged_environment(const std::map<std::string, std::string>& extra) {
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e) {
    const std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('='));
    if (!extra.count(name)) env.push_back(entry);
  }
  for (const auto& [name, value] : extra) env.push_back(name + "=" + value);
  return env;
}

// Runs in the forked child: only async-signal-safe calls until exec.
[[noreturn]] void exec_child(const char* command, char* const* envp, int output_fd, int death_signal, pid_t launcher) {
  setsid();
  prctl(PR_SET_PDEATHSIG, death_signal);
  if (getppid() != launcher) _exit(127);  // the launcher died before prctl
  // Dispositions the launcher ignores would be inherited through exec, and
  // its handlers must not catch a stop meant for the command.
  for (int s : {SIGINT, SIGTERM, SIGPIPE, SIGHUP, SIGQUIT, SIGCHLD}) signal(s, SIG_DFL);
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  const int devnull = open("/dev/null", O_RDONLY);
  if (devnull >= 0) dup2(devnull, STDIN_FILENO);
  dup2(output_fd, STDOUT_FILENO);
  dup2(output_fd, STDERR_FILENO);
  close_range(3, ~0U, 0);  // LCM sockets and other commands' pipes stay with the launcher
  char* const argv[] = {const_cast<char*>("sh"), const_cast<char*>("-c"), const_cast<char*>(command), nullptr};
  execve("/bin/sh", argv, envp);
  _exit(127);
}

// Length of a leading NAME=VALUE word (VALUE may be quoted), or 0.
size_t assignment_length(const std::string& s, size_t begin) {
  size_t i = begin;
  if (i >= s.size() || !(std::isalpha(static_cast<unsigned char>(s[i])) || s[i] == '_')) return 0;
  while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_')) ++i;
  if (i >= s.size() || s[i] != '=') return 0;
  char quote = 0;
  for (++i; i < s.size(); ++i) {
    const char c = s[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == ' ' || c == '\t') {
      break;
    }
  }
  return quote ? 0 : i - begin;
}

}  // namespace

ChildProcess spawn_shell_command(const std::string& command, const std::map<std::string, std::string>& environment,
                                 int death_signal) {
  std::vector<std::string> env = merged_environment(environment);
  std::vector<char*> envp;
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);

  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::system_error(errno, std::generic_category(), "pipe");
  const pid_t launcher = getpid();
  // Signals wait until the child has reset the launcher's handlers: a stop
  // sent right after the fork must not land in a copy of our handler.
  sigset_t all, previous;
  sigfillset(&all);
  pthread_sigmask(SIG_SETMASK, &all, &previous);
  const pid_t pid = fork();
  if (pid != 0) pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (pid < 0) {
    const int err = errno;
    close(fds[0]);
    close(fds[1]);
    throw std::system_error(err, std::generic_category(), "fork");
  }
  if (pid == 0) exec_child(command.c_str(), envp.data(), fds[1], death_signal, launcher);
  close(fds[1]);
  fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
  // Also from this side, so a signal sent right away reaches the new group.
  setpgid(pid, pid);
  return {pid, fds[0]};
}

std::string exec_form(const std::string& command) {
  static const char* kControl = ";&|()`\n{}<>";
  if (command.find_first_of(kControl) != std::string::npos || command.find("$(") != std::string::npos) return command;
  size_t i = command.find_first_not_of(" \t");
  if (i == std::string::npos) return command;
  while (const size_t n = assignment_length(command, i)) {
    i = command.find_first_not_of(" \t", i + n);
    if (i == std::string::npos) return command;  // assignments only
  }
  // Keywords and special builtins cannot follow exec ("exec exit 3" fails).
  static const std::set<std::string> kShellWords = {
      "!",        ".",    ":",        "[",      "alias",   "break", "case",    "cd",   "command",
      "continue", "eval", "exec",     "exit",   "export",  "for",   "getopts", "hash", "if",
      "local",    "read", "readonly", "return", "set",     "shift", "source",  "test", "times",
      "trap",     "type", "ulimit",   "umask",  "unalias", "unset", "until",   "wait", "while"};
  const std::string first = command.substr(i, command.find_first_of(" \t", i) - i);
  if (kShellWords.count(first)) return command;
  return command.substr(0, i) + "exec " + command.substr(i);
}

std::string describe_wait_status(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    const char* name = strsignal(s);
    return "signal " + std::to_string(s) + " (" + (name ? name : "?") + ")";
  }
  return "status " + std::to_string(status);
}

}  // namespace ivoa::launcher
