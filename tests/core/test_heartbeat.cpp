#include <gtest/gtest.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa {
namespace {

TEST(Heartbeat, PublishesCountersLatencyAndLastError) {
  Bus bus("memq://");
  std::vector<process_status_t> got;
  bus.subscribe<process_status_t>("HB_TEST_STATUS",
                                  [&](const process_status_t& s, const ReceiveInfo&) { got.push_back(s); });
  Heartbeat hb(bus, "tester", "HB_TEST_STATUS", 3600.0);
  hb.count_in(5);
  hb.count_out(4);
  hb.count_dropped(1);
  hb.bad_input("frame 3: wrong size");
  hb.bad_input("frame 4: wrong size");
  hb.latency(2.0);
  hb.latency(4.0);
  hb.set_counter("frames_skipped", 9);
  hb.set_state("running");
  hb.tick();  // first tick publishes
  hb.tick();  // within the period: does not
  for (int i = 0; i < 20 && got.empty(); ++i) bus.handle(10);
  bus.handle(10);
  ASSERT_EQ(got.size(), 1u);
  const process_status_t& s = got[0];
  EXPECT_EQ(s.name, "tester");
  EXPECT_EQ(s.messages_in, 5);
  EXPECT_EQ(s.messages_out, 4);
  EXPECT_EQ(s.dropped, 1);
  EXPECT_EQ(s.bad_input, 2);
  EXPECT_EQ(s.last_error, "frame 4: wrong size");
  EXPECT_DOUBLE_EQ(s.latency_ms_mean, 3.0);
  EXPECT_DOUBLE_EQ(s.latency_ms_max, 4.0);
  EXPECT_EQ(s.state, "running");
  ASSERT_EQ(s.num_counters, 1);
  EXPECT_EQ(s.counter_names[0], "frames_skipped");
  EXPECT_EQ(s.counter_values[0], 9);
  // Latency statistics restart each period.
  EXPECT_DOUBLE_EQ(hb.snapshot().latency_ms_max, 0.0);
}

// A message quoting its input: a 3 MB detector name made every heartbeat 3 MB.
TEST(Heartbeat, AnErrorIsKeptCutToItsStart) {
  Bus bus("memq://");
  Heartbeat hb(bus, "tester", "HB_TEST_STATUS", 3600.0);
  const std::string text = "detector '" + std::string(3'000'000, 'x') + "'";
  hb.bad_input(text);
  const std::string kept = hb.snapshot().last_error;
  EXPECT_EQ(kept, text.substr(0, kMaxErrorChars) + "... (2999011 more characters)");
}

TEST(Heartbeat, SummaryGivesTheCountsAndTheCountersThatAreNotZero) {
  Bus bus("memq://");
  Heartbeat hb(bus, "tester", "HB_SUMMARY_TEST_STATUS", 3600.0);
  hb.count_in(5);
  hb.count_out(3);
  hb.count_dropped(1);
  hb.bad_input("frame 3: wrong size");
  hb.set_counter(kFramesWithoutCalibration, 2);
  hb.set_counter("grids_missing", 0);
  EXPECT_EQ(hb.summary(), "in 5, out 3, dropped 1, bad 1, frames_without_calibration 2");
}

}  // namespace
}  // namespace ivoa
