// The launcher's --status-file JSON: what scripts read after a run.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ivoa/launcher/status_report.hpp"

namespace ivoa::launcher {
namespace {

StatusRow row(const std::string& name) {
  StatusRow r;
  r.command.name = name;
  r.command.state = RunState::kStopped;
  r.command.exit_code = 0;
  return r;
}

TEST(StatusJson, CarriesEachHeartbeatsOwnCounters) {
  StatusRow monitor = row("depth_monitor");
  process_status_t h;
  h.name = "depth_monitor";
  h.messages_in = 12;
  h.bad_input = 1;
  h.counter_names = {"frames_without_calibration", "stereo_unmatched"};
  h.counter_values = {2, 0};
  monitor.heartbeat = h;
  const std::string json = format_status_json({monitor, row("silent")}, RunSummary{"record.pmd", "robot", 12, "", 0});
  EXPECT_NE(json.find("\"bad_input\": 1"), std::string::npos) << json;
  EXPECT_NE(json.find("\"counters\": {\"frames_without_calibration\": 2, \"stereo_unmatched\": 0}}}"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"name\": \"silent\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"heartbeat\": null}"), std::string::npos) << json;
}

TEST(StatusJson, AHeartbeatWithoutCountersHasAnEmptyObject) {
  StatusRow logger = row("logger");
  logger.heartbeat = process_status_t{};
  const std::string json = format_status_json({logger}, RunSummary{});
  EXPECT_NE(json.find("\"counters\": {}}}"), std::string::npos) << json;
}

// A command killed and respawned: the table counts what every instance did,
// and the last heartbeat of the one killed is not shown as a live state.
TEST(StatusTable, CountsEveryInstanceAndSaysWhenTheSenderHasEnded) {
  StatusRow detector = row("stereo_detector");
  detector.command.state = RunState::kRespawning;
  process_status_t h;
  h.messages_in = 30;
  h.messages_out = 29;
  h.dropped = 1;
  h.state = "running";
  detector.heartbeat = h;
  detector.earlier = InstanceCounts{1, 100, 98, 2, 3};
  detector.heartbeat_sender_ended = true;
  const std::string table = format_status_table({detector});
  EXPECT_NE(table.find("     130      127      3     3"), std::string::npos) << table;
  EXPECT_NE(table.find("ended; last said running (0s ago)"), std::string::npos) << table;
  const std::string json = format_status_json({detector}, RunSummary{});
  EXPECT_NE(json.find("\"earlier_instances\": {\"instances\": 1, \"messages_in\": 100, \"messages_out\": 98, "
                      "\"dropped\": 2, \"bad_input\": 3}"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"messages_in\": 30,"), std::string::npos)
      << "the heartbeat's own counts stay its own: " << json;
}

}  // namespace
}  // namespace ivoa::launcher
