#pragma once
// A process that outlives a killed ivoa-launch and stops the commands it
// left running. The kernel's death signal (PR_SET_PDEATHSIG) reaches only
// the process a command runs as: for a compound command (`a; b`, a
// pipeline) that is the shell, and its children would run on. The watchdog
// is told each command's process group as it starts and once it has gone;
// if the launcher ends without standing it down (SIGKILL, a crash), it
// sends each group's other processes the command's stop signal and
// SIGKILLs what is left of the group after its stop_time_allowed.
#include <sys/types.h>

namespace ivoa::launcher {

class GroupWatchdog {
 public:
  // Forks the watchdog. Call it before any thread starts. If the fork
  // fails, the object does nothing (the kernel's death signal remains).
  // With main's argc/argv, the watchdog writes its own title over its copy
  // of the launcher's command line, so that `pkill -f` aimed at the
  // launcher does not take the watchdog with it.
  GroupWatchdog(int argc = 0, char** argv = nullptr);
  // Stands the watchdog down and waits for it: the launcher has stopped
  // (or SIGKILLed) everything itself.
  ~GroupWatchdog();
  GroupWatchdog(const GroupWatchdog&) = delete;
  GroupWatchdog& operator=(const GroupWatchdog&) = delete;

  bool running() const { return pid_ > 0; }
  void watch(pid_t pgid, int stop_signal, double stop_time_allowed_s);
  void forget(pid_t pgid);

 private:
  void send(int kind, pid_t pgid, int stop_signal, double stop_time_allowed_s);

  pid_t pid_ = -1;
  int fd_ = -1;  // write end; its EOF without a stand-down is the launcher's death
};

}  // namespace ivoa::launcher
