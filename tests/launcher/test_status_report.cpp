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

}  // namespace
}  // namespace ivoa::launcher
