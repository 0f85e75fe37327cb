#pragma once
// Starting one command: /bin/sh -c in a new session (so its own process
// group, away from the terminal's Ctrl-C), stdin from /dev/null, stdout
// and stderr into one pipe the launcher reads.
#include <map>
#include <string>
#include <sys/types.h>

namespace ivoa::launcher {

struct ChildProcess {
  pid_t pid = -1;      // also the process group id
  int output_fd = -1;  // read end, non-blocking, close-on-exec
};

// Throws std::system_error if the pipe or fork fails. `environment` is added
// to (and overrides) the launcher's own. `death_signal` is sent to the
// command if the launcher dies without stopping it.
ChildProcess spawn_shell_command(const std::string& command, const std::map<std::string, std::string>& environment,
                                 int death_signal);

// The command with "exec" put before its program when it is one simple
// command ("A=1 prog args" -> "A=1 exec prog args"), so the program replaces
// the shell: its pid is the command's, and signals reach it directly.
// Anything with shell control syntax is returned unchanged.
std::string exec_form(const std::string& command);

// "exit code 3", "signal 9 (Killed)" for a waitpid() status.
std::string describe_wait_status(int status);

}  // namespace ivoa::launcher
