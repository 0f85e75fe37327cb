// The launcher's view of heartbeats: matched to commands, and the latency
// column keeps the last measured value through idle heartbeats.
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>

#include "heartbeat_monitor.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/launcher/supervisor.hpp"

namespace ivoa::launcher {
namespace {

Supervisor idle_supervisor(const std::string& name) {
  LaunchCommand c;
  c.spec.name = name;
  c.spec.exec = c.shell_command = "true";
  return Supervisor(
      {c}, SupervisorOptions{}, [](const std::string&, const std::string&) {},
      [](const std::string&, const std::string&) {});
}

process_status_t remote_status(const std::string& name, int64_t out, double latency_mean, double latency_max) {
  process_status_t s{};
  s.name = name;
  s.host = "another-machine";  // matched by name, not by process group
  s.messages_out = out;
  s.latency_ms_mean = latency_mean;
  s.latency_ms_max = latency_max;
  return s;
}

TEST(LauncherHeartbeats, IdleHeartbeatKeepsTheLastMeasuredLatency) {
  Bus bus("memq://");
  const Supervisor supervisor = idle_supervisor("detector");
  HeartbeatMonitor monitor(bus, "TEST_HB_LATENCY", supervisor);

  auto publish = [&](process_status_t s) {
    bus.publish("TEST_HB_LATENCY", s);
    monitor.drain();
    const auto latest = monitor.latest("detector");
    EXPECT_TRUE(latest.has_value());
    return latest ? latest->status : process_status_t{};
  };
  EXPECT_DOUBLE_EQ(publish(remote_status("detector", 10, 12.5, 20)).latency_ms_mean, 12.5);
  const process_status_t idle = publish(remote_status("detector", 10, 0, 0));
  EXPECT_DOUBLE_EQ(idle.latency_ms_mean, 12.5);
  EXPECT_DOUBLE_EQ(idle.latency_ms_max, 20);
  EXPECT_DOUBLE_EQ(publish(remote_status("detector", 30, 3, 4)).latency_ms_mean, 3);
  EXPECT_EQ(publish(remote_status("detector", 30, 0, 0)).messages_out, 30);

  process_status_t stranger = remote_status("stranger", 1, 1, 1);
  bus.publish("TEST_HB_LATENCY", stranger);
  monitor.drain();
  EXPECT_FALSE(monitor.latest("stranger").has_value());
}

process_status_t local_status(int pid, const std::string& state) {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  process_status_t s{};
  s.name = "whatever-it-calls-itself";  // matched by process group, not by name
  s.host = host;
  s.pid = pid;
  s.state = state;
  return s;
}

// A process's last heartbeat, sent as it stops, is often read only after the
// launcher has reaped it: it still belongs to its command, so the final
// status table shows "stopped", not the state before.
TEST(LauncherHeartbeats, HeartbeatsReadAfterTheProcessEndedStillCount) {
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);  // as ivoa-launch: reap the group's orphans
  SupervisorOptions options;
  options.reap_orphans = true;
  LaunchCommand c;
  c.spec.name = "family";
  c.spec.exec = c.shell_command = "sleep 30 & echo $!; wait";  // the shell leads the group, sleep is in it
  c.spec.stop_signal = SIGTERM;                                // a shell's background job ignores SIGINT
  int child = 0;
  Supervisor supervisor(
      {c}, options, [&](const std::string&, const std::string& line) { child = std::stoi(line); },
      [](const std::string&, const std::string&) {});
  Bus bus("memq://");
  HeartbeatMonitor monitor(bus, "TEST_HB_ENDED", supervisor);
  const auto heard = [&](const process_status_t& s) {
    process_status_t copy = s;
    bus.publish("TEST_HB_ENDED", copy);
    monitor.drain();
    const auto latest = monitor.latest("family");
    return latest ? latest->status.state : std::string("(none)");
  };
  supervisor.start_all();
  for (int i = 0; i < 100 && child == 0; ++i) supervisor.step(50);
  ASSERT_GT(child, 0);
  const int leader = supervisor.status("family").pid;
  EXPECT_EQ(heard(local_status(child, "running")), "running");

  supervisor.stop_all();
  for (int i = 0; i < 100 && supervisor.busy(); ++i) supervisor.step(50);
  ASSERT_FALSE(supervisor.busy());
  EXPECT_EQ(heard(local_status(child, "stopped")), "stopped") << "a pid heard from while it ran";
  EXPECT_EQ(heard(local_status(leader, "stopped by leader")), "stopped by leader") << "the group's leader";
  EXPECT_EQ(heard(local_status(leader + 100000, "stranger")), "stopped by leader") << "a pid never in the group";
  prctl(PR_SET_CHILD_SUBREAPER, 0);
}

// A respawned command is a new instance: the counts its earlier instances
// reached (their last heartbeats) are kept beside the newest's, each once,
// even when a killed instance's last heartbeat is read after the new one's.
TEST(LauncherHeartbeats, EarlierInstancesCountsAreKeptOnceEach) {
  Bus bus("memq://");
  const Supervisor supervisor = idle_supervisor("detector");
  HeartbeatMonitor monitor(bus, "TEST_HB_INSTANCES", supervisor);
  auto publish = [&](int pid, int64_t in) {
    process_status_t s = remote_status("detector", in, 1, 1);
    s.pid = pid;
    s.messages_in = in;
    bus.publish("TEST_HB_INSTANCES", s);
    monitor.drain();
    return *monitor.latest("detector");
  };
  EXPECT_EQ(publish(100, 10).earlier.instances, 0);
  HeartbeatMonitor::Latest now = publish(200, 5);  // respawned
  EXPECT_EQ(now.earlier.instances, 1);
  EXPECT_EQ(now.earlier.messages_in, 10);
  now = publish(100, 12);  // the first instance's last word, read late
  EXPECT_EQ(now.status.messages_in + now.earlier.messages_in, 17) << "12 from the first, 5 from the second";
  now = publish(200, 9);
  EXPECT_EQ(now.earlier.instances, 1);
  EXPECT_EQ(now.status.messages_in + now.earlier.messages_in, 21);
  EXPECT_EQ(now.earlier.messages_out, 12);
}

process_status_t instance_status(int pid, int64_t start_utime, int64_t in, double latency) {
  process_status_t s = remote_status("detector", in, latency, latency);
  s.pid = pid;
  s.start_utime = start_utime;
  s.messages_in = in;
  s.state = "running";
  return s;
}

// An instance is known by its host, pid and start time: a respawn that gets
// the pid of the one before (a container's, or after pid wrap-around) is
// another instance, and does not inherit its latency; so is a process of
// the same name and pid on another host.
TEST(LauncherHeartbeats, AReusedPidIsAnotherInstance) {
  Bus bus("memq://");
  const Supervisor supervisor = idle_supervisor("detector");
  HeartbeatMonitor monitor(bus, "TEST_HB_REUSED", supervisor);
  auto publish = [&](const process_status_t& s) {
    process_status_t copy = s;
    bus.publish("TEST_HB_REUSED", copy);
    monitor.drain();
    return *monitor.latest("detector");
  };
  publish(instance_status(7, 1'000, 10, 40));
  HeartbeatMonitor::Latest now = publish(instance_status(7, 2'000, 3, 0));  // respawned with the same pid
  EXPECT_EQ(now.earlier.instances, 1);
  EXPECT_EQ(now.status.messages_in + now.earlier.messages_in, 13);
  EXPECT_DOUBLE_EQ(now.status.latency_ms_max, 0) << "no latency inherited from the instance before";
  process_status_t other_robot = instance_status(7, 2'000, 100, 1);
  other_robot.host = "another-robot";
  EXPECT_EQ(publish(other_robot).earlier.instances, 2);
}

// A killed local instance's last heartbeat, read after its respawned
// successor's, adds its counts but is not shown as the command's state:
// the supervisor says which process group is the command's now.
TEST(LauncherHeartbeats, AKilledInstancesLateHeartbeatDoesNotReplaceTheCurrentOnes) {
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  SupervisorOptions options;
  options.reap_orphans = true;
  options.respawn_delay_s = 0.05;
  LaunchCommand c;
  c.spec.name = "family";
  c.spec.exec = c.shell_command = "exec sleep 30";
  c.spec.auto_respawn = true;
  Supervisor supervisor(
      {c}, options, [](const std::string&, const std::string&) {}, [](const std::string&, const std::string&) {});
  Bus bus("memq://");
  HeartbeatMonitor monitor(bus, "TEST_HB_KILLED", supervisor);
  const auto heard = [&](int pid, const std::string& state, int64_t in) {
    process_status_t s = local_status(pid, state);
    s.start_utime = pid;
    s.messages_in = in;
    bus.publish("TEST_HB_KILLED", s);
    monitor.drain();
    return *monitor.latest("family");
  };
  supervisor.start_all();
  const int first = supervisor.status("family").pid;
  ASSERT_GT(first, 0);
  EXPECT_EQ(heard(first, "running", 10).status.state, "running");
  ASSERT_EQ(::kill(first, SIGKILL), 0);
  for (int i = 0; i < 200 && supervisor.status("family").pid == first; ++i) supervisor.step(20);
  const int second = supervisor.status("family").pid;
  ASSERT_NE(second, first);
  ASSERT_GT(second, 0);
  EXPECT_EQ(heard(second, "running", 2).earlier.instances, 1);
  const HeartbeatMonitor::Latest now = heard(first, "running (its last word)", 12);
  EXPECT_EQ(now.instance, second);
  EXPECT_EQ(now.status.state, "running");
  EXPECT_EQ(now.status.messages_in + now.earlier.messages_in, 14);
  supervisor.kill_all();
  prctl(PR_SET_CHILD_SUBREAPER, 0);
}

}  // namespace
}  // namespace ivoa::launcher
