// ivoa-log-play's player: split files as one stream, in order, channels by
// regex, damaged stretches skipped and reported, the pace. Played as fast as
// possible into memq://, so nothing here depends on timing.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/log_play/log_player.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/log_writer.hpp"
#include "logger_test_util.hpp"
#include "test_rig.hpp"

namespace ivoa::log_play {
namespace {

struct Played {
  std::string channel;
  std::vector<uint8_t> data;
};

// Writes events {channel, timestamp}; each payload is numbered by its timestamp.
std::vector<uint64_t> write_log(const std::string& path, const std::vector<std::pair<std::string, int64_t>>& events) {
  logio::LogWriter writer(path);
  std::vector<uint64_t> offsets;
  for (const auto& [channel, t] : events) {
    offsets.push_back(writer.bytes());
    const auto data = test::numbered_bytes(64, static_cast<uint8_t>(t));
    writer.write(channel, t, data.data(), data.size());
  }
  writer.close();
  return offsets;
}

struct PlayFixture {
  Bus bus{"memq://"};
  Heartbeat heartbeat{bus, "log_play", "TEST_LOG_PLAY_STATUS", 3600.0};
  std::vector<Played> played;

  PlayFixture() {
    bus.subscribe_raw("CAM|DEPTH|RIG", [this](const void* data, size_t size, const ReceiveInfo& info) {
      const auto* bytes = static_cast<const uint8_t*>(data);
      played.push_back({info.channel, {bytes, bytes + size}});
    });
  }
  PlayCounts play(const std::vector<std::string>& files, LogPlayerOptions options = {}) {
    options.speed = 0;
    LogPlayer player(bus, heartbeat, files, options);
    EXPECT_TRUE(player.play());
    while (bus.handle(0) > 0) {
    }
    return player.counts();
  }
};

TEST(LogPlay, SplitFilesPlayAsOneStreamInTheGivenOrder) {
  test::TempDir dir;
  const std::string a = dir.file("s.lcmlog.00"), b = dir.file("s.lcmlog.01");
  write_log(a, {{"RIG", 1}, {"CAM", 10}, {"DEPTH", 11}});
  write_log(b, {{"RIG", 1}, {"CAM", 20}, {"DEPTH", 21}});  // a split file starts with the older calibration
  PlayFixture f;
  const PlayCounts counts = f.play({a, b});
  EXPECT_EQ(counts.files_done, 2);
  EXPECT_EQ(counts.published, 6);
  ASSERT_EQ(f.played.size(), 6u);
  const std::vector<std::string> order{"RIG", "CAM", "DEPTH", "RIG", "CAM", "DEPTH"};
  for (size_t i = 0; i < order.size(); ++i) EXPECT_EQ(f.played[i].channel, order[i]) << i;
  EXPECT_EQ(f.played[4].data, test::numbered_bytes(64, 20)) << "payloads pass unchanged";
  EXPECT_EQ(f.heartbeat.snapshot().messages_out, 6);
  EXPECT_EQ(f.heartbeat.counter("files_done"), 2);
  EXPECT_EQ(f.heartbeat.snapshot().state, "finished");
}

TEST(LogPlay, ChannelsAreChosenByWholeNameRegex) {
  test::TempDir dir;
  const std::string log = dir.file("s.lcmlog");
  write_log(log, {{"RIG", 1}, {"CAM", 2}, {"CAM_OUT", 3}, {"DEPTH", 4}});
  PlayFixture f;
  LogPlayerOptions options;
  options.channels = "CAM.*|RIG";
  options.exclude = "CAM_OUT";
  const PlayCounts counts = f.play({log}, options);
  EXPECT_EQ(counts.published, 2);
  EXPECT_EQ(counts.filtered_out, 2);
  ASSERT_EQ(f.played.size(), 2u);
  EXPECT_EQ(f.played[0].channel, "RIG");
  EXPECT_EQ(f.played[1].channel, "CAM");
}

TEST(LogPlay, ADamagedStretchIsSkippedReportedAndPlayGoesOn) {
  test::TempDir dir;
  const std::string a = dir.file("s.lcmlog.00"), b = dir.file("s.lcmlog.01");
  const auto offsets = write_log(a, {{"CAM", 1}, {"DEPTH", 2}, {"CAM", 3}});
  write_log(b, {{"CAM", 4}});
  {
    std::fstream file(a, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(static_cast<std::streamoff>(offsets[1]));
    file.put(0);  // the second event's sync word
  }
  PlayFixture f;
  const PlayCounts counts = f.play({a, b});
  EXPECT_EQ(counts.damaged, 1);
  EXPECT_EQ(counts.published, 3);
  EXPECT_EQ(counts.files_done, 2);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 1);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find(a + ": byte " + std::to_string(offsets[1])), std::string::npos)
      << f.heartbeat.snapshot().last_error;
}

TEST(LogPlay, AnUnreadableFileStopsEverythingBeforePlay) {
  test::TempDir dir;
  const std::string good = dir.file("s.lcmlog.00"), missing = dir.file("s.lcmlog.01");
  write_log(good, {{"CAM", 1}});
  PlayFixture f;
  try {
    LogPlayer player(f.bus, f.heartbeat, {good, missing}, {});
    FAIL() << "a missing file was accepted";
  } catch (const logio::LogReadError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  EXPECT_THROW(LogPlayer(f.bus, f.heartbeat, {good}, LogPlayerOptions{1.0, "CAM(", ""}), std::invalid_argument);
  EXPECT_TRUE(f.played.empty());
}

TEST(LogPlay, AFileThatIsNoLogIsReportedAndTheOthersPlay) {
  test::TempDir dir;
  const std::string text = dir.file("notes.txt"), log = dir.file("s.lcmlog");
  std::ofstream(text) << "not a log\n";
  write_log(log, {{"CAM", 1}});
  PlayFixture f;
  const PlayCounts counts = f.play({text, log});
  EXPECT_EQ(counts.not_logs, 1);
  EXPECT_EQ(counts.published, 1);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 1);
}

TEST(LogPlay, AnEmptyFileHoldsNoEventAndIsReported) {
  test::TempDir dir;
  const std::string empty = dir.file("empty.lcmlog"), log = dir.file("b.lcmlog");
  std::ofstream{empty};
  write_log(log, {{"CAM", 1}});
  PlayFixture f;
  const PlayCounts counts = f.play({empty, log});
  EXPECT_EQ(counts.not_logs, 1);  // exit code 3, as --help says
  EXPECT_EQ(counts.published, 1);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 1);  // and in the status table
}

TEST(LogPlay, EventsAreDueAtTheirLogTimeOverTheSpeed) {
  PlayClock clock(1.0, 0.0);
  EXPECT_DOUBLE_EQ(clock.due_ms(1'000'000), 0.0);
  EXPECT_DOUBLE_EQ(clock.due_ms(1'500'000), 500.0);
  EXPECT_DOUBLE_EQ(clock.due_ms(900'000), 500.0) << "earlier than the latest event: at once";
  PlayClock twice(2.0, 0.0);
  twice.due_ms(1'000'000);
  EXPECT_DOUBLE_EQ(twice.due_ms(1'500'000), 250.0);
  PlayClock fastest(0.0, 0.0);
  fastest.due_ms(1'000'000);
  EXPECT_DOUBLE_EQ(fastest.due_ms(1'500'000), 0.0) << "as fast as possible";
}

TEST(LogPlay, APauseLongerThanTheMaximumIsCutToIt) {
  PlayClock clock(2.0, 10.0);
  EXPECT_DOUBLE_EQ(clock.due_ms(0), 0.0);
  EXPECT_DOUBLE_EQ(clock.due_ms(4'000'000), 2'000.0);
  EXPECT_EQ(clock.last_cut_us(), 0u) << "4 s is no long pause";
  EXPECT_DOUBLE_EQ(clock.due_ms(10'000'004'000'000), 7'000.0) << "a jump of 116 days plays as 10 s, at twice the pace";
  EXPECT_EQ(clock.last_cut_us(), 9'999'990'000'000u);
  EXPECT_DOUBLE_EQ(clock.due_ms(10'000'005'000'000), 7'500.0) << "and the pace goes on after it";
  EXPECT_EQ(clock.last_cut_us(), 0u);
  PlayClock extremes(1.0, 10.0);
  extremes.due_ms(INT64_MIN);
  EXPECT_DOUBLE_EQ(extremes.due_ms(INT64_MAX), 10'000.0) << "log times of any sign and size";
}

TEST(LogPlay, AClockJumpIsNotWaitedOut) {
  test::TempDir dir;
  const std::string log = dir.file("s.lcmlog");
  write_log(log, {{"CAM", 1'000}, {"CAM", 10'000'000'001'000}, {"CAM", 10'000'000'002'000}});
  PlayFixture f;
  LogPlayerOptions options;
  options.max_gap_s = 0.01;  // at the recorded pace: 10 ms for the jump, 1 ms after it
  LogPlayer player(f.bus, f.heartbeat, {log}, options);
  ASSERT_TRUE(player.play());
  EXPECT_EQ(player.counts().published, 3);
  EXPECT_EQ(player.counts().shortened_pauses, 1);
  EXPECT_EQ(f.heartbeat.counter("shortened_pauses"), 1);
}

}  // namespace
}  // namespace ivoa::log_play
