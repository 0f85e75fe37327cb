// The supervisor with dummy commands: output lines, exit codes, stop
// signals, SIGKILL after stop_time_allowed, respawn with back-off, process
// groups. Waits are bounded; times are only checked against lower bounds
// the supervisor guarantees, or loose upper bounds.
#include <signal.h>
#include <sys/prctl.h>

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "ivoa/launcher/supervisor.hpp"
#include "test_rig.hpp"

namespace ivoa::launcher {
namespace {

using Clock = std::chrono::steady_clock;

LaunchCommand make_command(const std::string& name, const std::string& shell, bool respawn = false,
                           int stop_signal = SIGINT, double stop_time_allowed_s = 5) {
  LaunchCommand c;
  c.spec.name = name;
  c.spec.exec = shell;
  c.spec.auto_respawn = respawn;
  c.spec.stop_signal = stop_signal;
  c.spec.stop_time_allowed_s = stop_time_allowed_s;
  c.shell_command = shell;
  return c;
}

struct Recorder {
  std::vector<std::pair<std::string, std::string>> lines, events;
  std::vector<Clock::time_point> starts;
  OutputHandler output() {
    return [this](const std::string& n, const std::string& l) { lines.emplace_back(n, l); };
  }
  EventHandler event() {
    return [this](const std::string& n, const std::string& e) {
      events.emplace_back(n, e);
      if (e.rfind("started", 0) == 0) starts.push_back(Clock::now());
    };
  }
};

SupervisorOptions fast_respawn() {
  SupervisorOptions o;
  o.respawn_delay_s = 0.1;
  o.respawn_max_delay_s = 10;
  o.healthy_after_s = 60;
  return o;
}

// Steps until `done` or `limit_s` passes; returns whether `done` held.
template <class Pred>
bool step_until(Supervisor& s, Pred done, double limit_s = 10) {
  const auto end = Clock::now() + std::chrono::duration<double>(limit_s);
  while (Clock::now() < end) {
    if (done()) return true;
    s.step(50);
  }
  return done();
}

bool process_group_exists(int pgid) { return kill(-pgid, 0) == 0 || errno != ESRCH; }

TEST(LauncherSupervisor, CapturesOutputLinesAndExitCode) {
  Recorder r;
  Supervisor s({make_command("talker", "echo one; echo two >&2; printf 'no newline'; exit 3")}, fast_respawn(),
               r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return !s.busy(); }));
  const CommandStatus st = s.status("talker");
  EXPECT_EQ(st.state, RunState::kStopped);
  EXPECT_EQ(st.exit_code, 3);
  EXPECT_TRUE(st.failed);
  EXPECT_EQ(st.restarts, 0) << "not auto_respawn";
  using Line = std::pair<std::string, std::string>;
  EXPECT_EQ(r.lines, (std::vector<Line>{{"talker", "one"}, {"talker", "two"}, {"talker", "no newline"}}));
}

TEST(LauncherSupervisor, CleanExitIsNotAFailure) {
  Recorder r;
  Supervisor s({make_command("ok", "true")}, fast_respawn(), r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return !s.busy(); }));
  EXPECT_EQ(s.status("ok").exit_code, 0);
  EXPECT_FALSE(s.status("ok").failed);
}

TEST(LauncherSupervisor, StopSendsTheCommandsStopSignal) {
  Recorder r;
  Supervisor s({make_command("sleeper", "sleep 30", false, SIGTERM, 10)}, fast_respawn(), r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return s.status("sleeper").state == RunState::kRunning; }));
  s.stop("sleeper");
  ASSERT_TRUE(step_until(
      s, [&] { return !s.busy(); }, 5))
      << "SIGTERM ends sleep long before stop_time_allowed";
  const CommandStatus st = s.status("sleeper");
  EXPECT_EQ(st.exit_signal, SIGTERM);
  EXPECT_FALSE(st.killed);
  EXPECT_FALSE(st.failed) << "a requested stop is not a failure";
}

TEST(LauncherSupervisor, CommandIgnoringItsStopSignalIsKilledAfterStopTimeAllowed) {
  Recorder r;
  const double allowed = 0.5;
  // The shell ignores SIGINT; so does sleep, which inherits the disposition.
  Supervisor s({make_command("stubborn", "trap '' INT; sleep 30", false, SIGINT, allowed)}, fast_respawn(), r.output(),
               r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return s.status("stubborn").uptime_s > 0.3; }));
  const auto stop_sent = Clock::now();
  s.stop("stubborn");
  ASSERT_TRUE(step_until(
      s, [&] { return !s.busy(); }, 10));
  const double took = std::chrono::duration<double>(Clock::now() - stop_sent).count();
  const CommandStatus st = s.status("stubborn");
  EXPECT_TRUE(st.killed);
  EXPECT_EQ(st.exit_signal, SIGKILL);
  EXPECT_GE(took, allowed) << "SIGKILL only after stop_time_allowed";
  EXPECT_LT(took, 8.0);
}

TEST(LauncherSupervisor, RespawnsWithDoublingBackOff) {
  Recorder r;
  Supervisor s({make_command("crasher", "exit 1", true)}, fast_respawn(), r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(
      s, [&] { return s.status("crasher").restarts >= 3; }, 10));
  s.stop("crasher");
  ASSERT_TRUE(step_until(s, [&] { return !s.busy(); }));
  std::vector<std::string> delays;
  for (const auto& [name, e] : r.events)
    if (e.rfind("respawning in", 0) == 0) delays.push_back(e);
  ASSERT_GE(delays.size(), 3u);
  EXPECT_EQ(delays[0], "respawning in 0.1 s");
  EXPECT_EQ(delays[1], "respawning in 0.2 s");
  EXPECT_EQ(delays[2], "respawning in 0.4 s");
  ASSERT_GE(r.starts.size(), 4u);
  // Each start waits at least its back-off after the previous one.
  for (size_t k = 1; k < 4; ++k)
    EXPECT_GE(std::chrono::duration<double>(r.starts[k] - r.starts[k - 1]).count(), 0.1 * (1 << (k - 1)) * 0.99);
}

TEST(LauncherSupervisor, BackOffIsCappedAndResetAfterAHealthyRun) {
  Recorder r;
  SupervisorOptions o = fast_respawn();
  o.respawn_max_delay_s = 0.2;
  Supervisor capped({make_command("crasher", "exit 1", true)}, o, r.output(), r.event());
  capped.start_all();
  ASSERT_TRUE(step_until(capped, [&] { return capped.status("crasher").restarts >= 4; }));
  capped.stop_all();
  ASSERT_TRUE(step_until(capped, [&] { return !capped.busy(); }));
  for (const auto& [name, e] : r.events)
    if (e.rfind("respawning in", 0) == 0) {
      EXPECT_TRUE(e == "respawning in 0.1 s" || e == "respawning in 0.2 s") << e;
    }

  Recorder healthy;
  o = fast_respawn();
  o.healthy_after_s = 0.2;
  Supervisor reset({make_command("slow_crasher", "sleep 0.3; exit 1", true)}, o, healthy.output(), healthy.event());
  reset.start_all();
  ASSERT_TRUE(step_until(reset, [&] { return reset.status("slow_crasher").restarts >= 3; }));
  for (const auto& [name, e] : healthy.events)
    if (e.rfind("respawning in", 0) == 0) {
      EXPECT_EQ(e, "respawning in 0.1 s") << "each run lasted past healthy_after";
    }
}

TEST(LauncherSupervisor, KilledCommandComesBack) {
  Recorder r;
  Supervisor s({make_command("worker", "sleep 30", true)}, fast_respawn(), r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return s.status("worker").state == RunState::kRunning; }));
  const int first_pid = s.status("worker").pid;
  ASSERT_EQ(kill(first_pid, SIGKILL), 0);
  ASSERT_TRUE(step_until(s, [&] {
    const auto st = s.status("worker");
    return st.state == RunState::kRunning && st.pid != first_pid;
  }));
  EXPECT_EQ(s.status("worker").restarts, 1);
  EXPECT_EQ(s.status("worker").exit_signal, SIGKILL);
}

TEST(LauncherSupervisor, StoppingACommandStopsItsWholeProcessGroup) {
  test::TempDir dir;
  const std::string pid_file = dir.file("child.pid");
  Recorder r;
  // As ivoa-launch does: orphans of the command come to this process, which
  // reaps them, so the emptied group is not kept alive by zombies.
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  SupervisorOptions o = fast_respawn();
  o.reap_orphans = true;
  // The shell stays (two commands), with a background child in its group.
  Supervisor s({make_command("family", "sleep 30 & echo $! > " + pid_file + "; wait", false, SIGTERM)}, o, r.output(),
               r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return std::ifstream(pid_file).peek() != EOF; }));
  const int group = s.status("family").pid;
  int child = 0;
  std::ifstream(pid_file) >> child;
  ASSERT_GT(child, 0);
  EXPECT_EQ(getpgid(child), group) << "the child is in the command's group";
  s.stop_all();
  ASSERT_TRUE(step_until(s, [&] { return !s.busy(); }));
  EXPECT_FALSE(process_group_exists(group));
  EXPECT_FALSE(s.status("family").killed) << "SIGTERM reached the whole group";
  prctl(PR_SET_CHILD_SUBREAPER, 0);
}

TEST(LauncherSupervisor, RestartStartsAgainAfterTheStop) {
  Recorder r;
  Supervisor s({make_command("svc", "sleep 30")}, fast_respawn(), r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return s.status("svc").state == RunState::kRunning; }));
  const int first = s.status("svc").pid;
  s.restart("svc");
  ASSERT_TRUE(
      step_until(s, [&] { return s.status("svc").pid != first && s.status("svc").state == RunState::kRunning; }));
  EXPECT_EQ(s.status("svc").restarts, 1);
  EXPECT_THROW(s.start("nope"), std::out_of_range);
}

TEST(LauncherSupervisor, CommandsSeeTheExtraEnvironment) {
  Recorder r;
  SupervisorOptions o = fast_respawn();
  o.environment = {{"IVOA_TEST_VALUE", "forty two"}};
  Supervisor s({make_command("env", "echo \"$IVOA_TEST_VALUE\"")}, o, r.output(), r.event());
  s.start_all();
  ASSERT_TRUE(step_until(s, [&] { return !s.busy(); }));
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_EQ(r.lines[0].second, "forty two");
}

}  // namespace
}  // namespace ivoa::launcher
