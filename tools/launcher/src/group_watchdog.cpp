#include "ivoa/launcher/group_watchdog.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>

namespace ivoa::launcher {
namespace {

// One record on the pipe: 16 bytes, so each write is atomic.
enum Kind : int32_t { kWatch = 1, kForget = 2, kStandDown = 3 };
struct Record {
  int32_t kind, pgid, stop_signal, stop_time_ms;
};

struct WatchedGroup {
  pid_t pgid;
  int stop_signal;
  double deadline_s;  // after the launcher's death; then SIGKILL
  bool done;
};

// The watchdog never holds more groups than the launcher runs commands.
constexpr int kMaxGroups = 4096;
constexpr int kPollMs = 50;

double now_s() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

// Process group and state of `pid` from /proc/PID/stat ("pid (comm) S ppid pgrp ...");
// false if it has gone.
bool read_stat(pid_t pid, pid_t& pgrp, char& state) {
  char path[64], text[512];
  std::snprintf(path, sizeof(path), "/proc/%d/stat", static_cast<int>(pid));
  const int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const ssize_t n = read(fd, text, sizeof(text) - 1);
  close(fd);
  if (n <= 0) return false;
  text[n] = '\0';
  const char* paren = std::strrchr(text, ')');  // the name may hold spaces and parentheses
  int ppid = 0, group = 0;
  if (!paren || std::sscanf(paren + 1, " %c %d %d", &state, &ppid, &group) != 3) return false;
  pgrp = group;
  return true;
}

// Calls visit(pid, group index) for each live (not zombie) process in one of
// the groups not yet done.
template <typename Visit>
void for_each_member(WatchedGroup* groups, int count, Visit visit) {
  DIR* proc = opendir("/proc");
  if (!proc) return;
  while (const dirent* entry = readdir(proc)) {
    char* end = nullptr;
    const long pid = std::strtol(entry->d_name, &end, 10);
    if (pid <= 0 || *end != '\0') continue;
    pid_t pgrp = 0;
    char state = 0;
    if (!read_stat(static_cast<pid_t>(pid), pgrp, state) || state == 'Z' || state == 'X') continue;
    for (int i = 0; i < count; ++i)
      if (!groups[i].done && groups[i].pgid == pgrp) visit(static_cast<pid_t>(pid), i);
  }
  closedir(proc);
}

// The launcher died with these groups running. Their leaders had the
// kernel's death signal; the rest of each group gets the command's stop
// signal now, and whatever is left of it SIGKILL at its deadline.
void stop_orphaned_groups(WatchedGroup* groups, int count) {
  std::fprintf(stderr, "ivoa-launch ended without stopping its commands: the watchdog stops %d process group(s)\n",
               count);
  for_each_member(groups, count, [&](pid_t pid, int i) {
    if (pid != groups[i].pgid) kill(pid, groups[i].stop_signal);
  });
  for (int remaining = count; remaining > 0;) {
    bool alive[kMaxGroups] = {};
    for_each_member(groups, count, [&](pid_t, int i) { alive[i] = true; });
    const double now = now_s();
    for (int i = 0; i < count; ++i) {
      if (groups[i].done) continue;
      if (alive[i] && now < groups[i].deadline_s) continue;
      if (alive[i]) {
        std::fprintf(stderr, "ivoa-launch watchdog: process group %d still running: SIGKILL\n",
                     static_cast<int>(groups[i].pgid));
        kill(-groups[i].pgid, SIGKILL);
      }
      groups[i].done = true;
      --remaining;
    }
    if (remaining > 0) usleep(kPollMs * 1000);
  }
}

bool read_record(int fd, Record& r) {
  size_t got = 0;
  while (got < sizeof(r)) {
    const ssize_t n = read(fd, reinterpret_cast<char*>(&r) + got, sizeof(r) - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    got += static_cast<size_t>(n);
  }
  return true;
}

// The forked watchdog: follows the launcher's records until a stand-down
// (exit quietly) or EOF without one (the launcher died: stop what is left).
[[noreturn]] void run_watchdog(int fd) {
  static WatchedGroup groups[kMaxGroups];
  int count = 0;
  Record r{};
  while (read_record(fd, r)) {
    if (r.kind == kStandDown) _exit(0);
    if (r.kind == kForget) {
      for (int i = count - 1; i >= 0; --i)
        if (groups[i].pgid == r.pgid) groups[i] = groups[--count];
    } else if (r.kind == kWatch && count < kMaxGroups) {
      groups[count++] = {r.pgid, r.stop_signal, r.stop_time_ms / 1000.0, false};
    }
  }
  if (count == 0) _exit(0);
  const double died_at = now_s();
  for (int i = 0; i < count; ++i) groups[i].deadline_s += died_at;
  stop_orphaned_groups(groups, count);
  _exit(0);
}

// Writes `title` over the command line (the argv strings lie end to end),
// which is what ps and pkill -f read.
void retitle(int argc, char** argv, const char* title) {
  if (argc <= 0 || !argv) return;
  char* begin = argv[0];
  char* end = argv[argc - 1] + std::strlen(argv[argc - 1]);
  const size_t room = static_cast<size_t>(end - begin);
  std::memset(begin, 0, room + 1);
  std::memcpy(begin, title, std::min(room, std::strlen(title)));
}

// In the forked child: away from the terminal's Ctrl-C and hang-up, which
// are the launcher's to handle; only the pipe and stderr kept open, so
// whoever reads the launcher's stdout is not held up by the watchdog.
void detach_watchdog(int fd) {
  setsid();
  prctl(PR_SET_NAME, "ivoa-watchdog");
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) signal(s, SIG_IGN);
  const int devnull = open("/dev/null", O_RDWR);
  if (devnull >= 0) {
    dup2(devnull, STDIN_FILENO);
    dup2(devnull, STDOUT_FILENO);
  }
  dup2(fd, 3);
  close_range(4, ~0U, 0);
}

// `fd` moved to 3 or above (a launcher started with stdin or stdout closed
// gets 0 or 1 from pipe2, which the watchdog points at /dev/null); -1 on failure.
int above_standard_streams(int fd) {
  if (fd > STDERR_FILENO) return fd;
  const int moved = fcntl(fd, F_DUPFD_CLOEXEC, STDERR_FILENO + 1);
  close(fd);
  return moved;
}

}  // namespace

GroupWatchdog::GroupWatchdog(int argc, char** argv) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) return;
  fds[0] = above_standard_streams(fds[0]);
  fds[1] = above_standard_streams(fds[1]);
  if (fds[0] < 0 || fds[1] < 0) {
    if (fds[0] >= 0) close(fds[0]);
    if (fds[1] >= 0) close(fds[1]);
    return;
  }
  std::fflush(nullptr);  // nothing buffered twice
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return;
  }
  if (pid == 0) {
    close(fds[1]);
    char title[96];
    std::snprintf(title, sizeof(title), "ivoa-watchdog: stops launcher %d's commands if it dies", getppid());
    retitle(argc, argv, title);
    detach_watchdog(fds[0]);
    run_watchdog(3);
  }
  close(fds[0]);
  pid_ = pid;
  fd_ = fds[1];
}

GroupWatchdog::~GroupWatchdog() {
  if (!running()) return;
  send(kStandDown, 0, 0, 0);
  close(fd_);
  waitpid(pid_, nullptr, 0);
}

void GroupWatchdog::watch(pid_t pgid, int stop_signal, double stop_time_allowed_s) {
  send(kWatch, pgid, stop_signal, stop_time_allowed_s);
}

void GroupWatchdog::forget(pid_t pgid) { send(kForget, pgid, 0, 0); }

void GroupWatchdog::send(int kind, pid_t pgid, int stop_signal, double stop_time_allowed_s) {
  if (!running()) return;
  const double ms = std::clamp(stop_time_allowed_s * 1000.0, 0.0, 2147483647.0);
  const Record r{kind, pgid, stop_signal, static_cast<int32_t>(ms)};
  ssize_t n;
  do n = write(fd_, &r, sizeof(r));
  while (n < 0 && errno == EINTR);
}

}  // namespace ivoa::launcher
