// The launcher's watchdog on its own: a fake launcher (a forked child)
// watches process groups and dies without standing the watchdog down.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <initializer_list>

#include <gtest/gtest.h>

#include "ivoa/launcher/group_watchdog.hpp"
#include "test_rig.hpp"

namespace ivoa::launcher {
namespace {

// `sleep 300` as the leader of a new process group.
pid_t start_group() {
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    execl("/bin/sleep", "sleep", "300", static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid, pid);
  return pid;
}

struct Groups {
  pid_t kept = -1, stopped = -1;
};

// A fake launcher that watches two groups, forgets `kept` (as the launcher
// does once a command's group has gone) and exits without a stand-down, as
// a SIGKILLed one would. Returns the two groups' pids.
Groups run_fake_launcher() {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return {};
  const pid_t fake = fork();
  if (fake == 0) {
    close(pipe_fds[0]);
    GroupWatchdog watchdog;
    const Groups g{start_group(), start_group()};
    watchdog.watch(g.kept, SIGTERM, 0.5);
    watchdog.watch(g.stopped, SIGTERM, 0.5);
    watchdog.forget(g.kept);
    if (write(pipe_fds[1], &g, sizeof(g)) != sizeof(g)) _exit(1);
    _exit(0);  // no destructor: the watchdog sees the pipe end without a stand-down
  }
  close(pipe_fds[1]);
  Groups g;
  const bool got = read(pipe_fds[0], &g, sizeof(g)) == sizeof(g);
  close(pipe_fds[0]);
  waitpid(fake, nullptr, 0);
  return got ? g : Groups{};
}

TEST(GroupWatchdog, StopsTheGroupsStillWatchedWhenTheLauncherDiesAndNoOthers) {
  const Groups g = run_fake_launcher();
  ASSERT_GT(g.kept, 0);
  ASSERT_GT(g.stopped, 0);
  // The leader had no death signal here (the kernel's, in ivoa-launch): the
  // watchdog's SIGKILL after the 0.5 s allowed ends it.
  const bool stopped = test::processes_end_within({g.stopped}, 10);
  const bool kept_running = !test::process_has_ended(g.kept);
  for (const pid_t pid : {g.kept, g.stopped})  // only what still runs: an ended pid may be reused
    if (!test::process_has_ended(pid)) kill(pid, SIGKILL);
  EXPECT_TRUE(stopped) << "the watched group outlived its launcher";
  EXPECT_TRUE(kept_running) << "a forgotten group (its pid free for reuse) was signalled";
}

TEST(GroupWatchdog, AStandDownLeavesEveryGroupAlone) {
  const pid_t group = start_group();
  ASSERT_GT(group, 0);
  {
    GroupWatchdog watchdog;
    ASSERT_TRUE(watchdog.running());
    watchdog.watch(group, SIGTERM, 0.1);
  }  // the destructor stands it down and waits for it
  const bool running = !test::process_has_ended(group);
  kill(group, SIGKILL);
  waitpid(group, nullptr, 0);
  EXPECT_TRUE(running) << "the launcher stops its commands itself; the watchdog must not";
}

}  // namespace
}  // namespace ivoa::launcher
