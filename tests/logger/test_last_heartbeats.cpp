// ivoa-log-check's per-process digest: the newest heartbeat of each
// process by utime, whatever order the log holds them in; each pid a
// process ran as (a respawn is a second run); other messages ignored.
#include <gtest/gtest.h>

#include <string>

#include "ivoa/log_check/last_heartbeats.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::log_check {
namespace {

template <class Msg>
logio::LogEvent event_of(const std::string& channel, const Msg& msg) {
  logio::LogEvent event;
  event.channel = channel;
  event.data.resize(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(event.data.data(), 0, static_cast<int>(event.data.size()));
  return event;
}

process_status_t heartbeat(const std::string& name, int32_t pid, int64_t utime, const std::string& state, int64_t out) {
  process_status_t s{};  // lcm-gen types leave numbers uninitialised
  s.utime = utime;
  s.name = name;
  s.pid = pid;
  s.state = state;
  s.messages_out = out;
  return s;
}

TEST(LastHeartbeats, KeepsEachProcessesNewestAndCountsItsRuns) {
  LastHeartbeats digest;
  digest.add(event_of("PROCESS_STATUS", heartbeat("stereo_detector", 10, 1000, "running", 5)));
  digest.add(event_of("PROCESS_STATUS", heartbeat("stereo_detector", 11, 3000, "stopped", 40)));
  digest.add(event_of("PROCESS_STATUS", heartbeat("stereo_detector", 11, 2000, "running", 30)));  // late
  digest.add(event_of("PROCESS_STATUS", heartbeat("logger", 12, 2500, "recording", 0)));
  stereo_image_t frame{};
  frame.utime = 4000;
  digest.add(event_of("STEREO_IMAGES", frame));

  const auto& processes = digest.processes();
  ASSERT_EQ(processes.size(), 2u);
  const LastHeartbeat& detector = processes.at("stereo_detector");
  EXPECT_EQ(detector.status.state, "stopped");
  EXPECT_EQ(detector.status.messages_out, 40);
  EXPECT_EQ(detector.pids.size(), 2u);
  EXPECT_EQ(detector.heartbeats, 3);
  EXPECT_NE(digest.json().find("\"stereo_detector\": {\"state\": \"stopped\", \"pid\": 11, \"runs\": 2"),
            std::string::npos)
      << digest.json();
  EXPECT_NE(digest.table().find("stopped"), std::string::npos) << digest.table();
  EXPECT_NE(digest.table().find("the log closes before they stop"), std::string::npos) << digest.table();
}

// A process's own counters: the non-zero ones in the table (frames that
// never arrived show nowhere else), all of them in the JSON.
TEST(LastHeartbeats, ShowsEachProcessesOwnCounters) {
  LastHeartbeats digest;
  process_status_t s = heartbeat("stereo_detector", 10, 1000, "stopped", 51);
  s.counter_names = {"calibrations_applied", "frames_missed", "frames_without_calibration"};
  s.counter_values = {1, 7, 0};
  s.num_counters = 3;
  digest.add(event_of("PROCESS_STATUS", s));
  EXPECT_NE(digest.table().find("calibrations_applied 1, frames_missed 7\n"), std::string::npos) << digest.table();
  EXPECT_NE(digest.json().find("\"counters\": {\"calibrations_applied\": 1, \"frames_missed\": 7, "
                               "\"frames_without_calibration\": 0}"),
            std::string::npos)
      << digest.json();
}

// Text from the log reaches the terminal without its control bytes: an
// escape sequence in a process name cleared the screen.
TEST(LastHeartbeats, ControlBytesInHeartbeatTextAreNotPrinted) {
  LastHeartbeats digest;
  process_status_t s = heartbeat("evil\x1b[2J", 10, 1000, "run\ning", 1);
  s.counter_names = {"x\x07"};
  s.counter_values = {1};
  s.num_counters = 1;
  digest.add(event_of("PROCESS_STATUS", s));
  const std::string table = digest.table();
  EXPECT_EQ(table.find('\x1b'), std::string::npos) << table;
  EXPECT_NE(table.find("evil?[2J"), std::string::npos) << table;
  EXPECT_NE(table.find("run?ing"), std::string::npos) << table;
  EXPECT_NE(table.find("x? 1"), std::string::npos) << table;
  EXPECT_NE(digest.json().find("\"evil\\u001b[2J\""), std::string::npos) << digest.json();
}

TEST(LastHeartbeats, ALogWithoutHeartbeatsHasNoTable) {
  LastHeartbeats digest;
  stereo_image_t frame{};
  digest.add(event_of("STEREO_IMAGES", frame));
  EXPECT_TRUE(digest.processes().empty());
  EXPECT_EQ(digest.table(), "");
  EXPECT_EQ(digest.json(), "{}");
}

}  // namespace
}  // namespace ivoa::log_check
