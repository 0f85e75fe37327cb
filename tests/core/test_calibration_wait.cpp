// Inputs skipped before a calibration: counted, and one warning per wait.
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration_wait.hpp"
#include "ivoa/core/heartbeat.hpp"

namespace ivoa {
namespace {

TEST(CalibrationWait, CountsEverySkippedInputAndWarnsOncePerWait) {
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(16);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("calibration_wait_test", sink));
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "tester", "CALIBRATION_WAIT_TEST_STATUS", 3600.0);
  CalibrationWait wait(heartbeat, "RIG_CALIBRATION_TEST");
  EXPECT_EQ(heartbeat.counter(kFramesWithoutCalibration), 0);

  wait.skip("frame 1", ", which a two-view model needs");
  wait.skip("frame 2");
  wait.end();
  wait.skip("frame 7");
  spdlog::set_default_logger(previous);

  EXPECT_EQ(heartbeat.counter(kFramesWithoutCalibration), 3);
  EXPECT_EQ(heartbeat.bad_input_count(), 0);  // not bad input
  const auto lines = sink->last_formatted();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("skipping frame 1: no calibration yet on RIG_CALIBRATION_TEST, which a two-view model needs"),
            std::string::npos);
  EXPECT_NE(lines[1].find("skipping frame 7"), std::string::npos);
}

}  // namespace
}  // namespace ivoa
