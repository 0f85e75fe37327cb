// The launcher's view of heartbeats: matched to commands, and the latency
// column keeps the last measured value through idle heartbeats.
#include <gtest/gtest.h>

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
  process_status_t s;
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

}  // namespace
}  // namespace ivoa::launcher
