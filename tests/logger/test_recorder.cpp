// The logger's core without LCM: every accepted channel (known type or
// not) reaches the log, split files each start with the newest
// calibration, finish() writes out the whole queue, a full queue is
// counted, and a refused write leaves a readable log and says why.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <thread>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/logger/disk_reserve.hpp"
#include "ivoa/logger/recorder.hpp"
#include "ivoa/logger/sidecar.hpp"
#include "ivoa/process_status_t.hpp"
#include "logger_test_util.hpp"
#include "test_rig.hpp"

namespace ivoa::logger {
namespace {

using test::numbered_bytes;
using test::read_back;
using test::read_file;

RecorderOptions options_in(const test::TempDir& dir, const std::string& name = "rec.lcmlog") {
  RecorderOptions o;
  o.log.path = dir.file(name);
  o.log.identity.version = "test";
  return o;
}

template <class Msg>
std::vector<uint8_t> encoded(Msg msg) {
  set_counts(msg);
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::vector<uint8_t> calibration_payload(int64_t utime) { return encoded(to_message(test::make_test_rig(), utime)); }

std::vector<uint8_t> heartbeat_payload(const std::string& process) {
  process_status_t msg{};
  msg.utime = 1;
  msg.name = process;
  msg.state = "running";
  return encoded(msg);
}

void offer(Recorder& r, const std::string& channel, const std::vector<uint8_t>& data, int64_t timestamp = 1) {
  r.on_message(channel, timestamp, data.data(), data.size());
}

TEST(Recorder, LogsEveryChannelIncludingOnesOfNoKnownType) {
  test::TempDir dir;
  Recorder recorder(options_in(dir));
  const auto calibration = calibration_payload(5);
  const auto foreign = numbered_bytes(5000, 9);
  offer(recorder, "RIG_CALIBRATION", calibration, 10);
  offer(recorder, "SOMEONE_ELSES_CHANNEL", foreign, 11);
  ASSERT_TRUE(recorder.finish());
  const auto r = read_back(dir.file("rec.lcmlog"));
  ASSERT_TRUE(r.problems.empty());
  ASSERT_EQ(r.events.size(), 2u);
  EXPECT_EQ(r.events[0].data, calibration);
  EXPECT_EQ(r.events[1].channel, "SOMEONE_ELSES_CHANNEL");
  EXPECT_EQ(r.events[1].timestamp, 11);
  EXPECT_EQ(r.events[1].data, foreign);
  const std::string sidecar = read_file(sidecar_path(dir.file("rec.lcmlog")));
  EXPECT_NE(sidecar.find("\"SOMEONE_ELSES_CHANNEL\": {\"type\": \"unknown\""), std::string::npos) << sidecar;
  EXPECT_NE(sidecar.find("\"RIG_CALIBRATION\": {\"type\": \"ivoa.rig_calibration_t\""), std::string::npos);
  EXPECT_NE(sidecar.find("\"complete\": true"), std::string::npos);
  EXPECT_NE(sidecar.find("\"starts_with_calibration\": true"), std::string::npos);
}

TEST(Recorder, FiltersChannelsButAlwaysKeepsTheCalibration) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir);
  o.channels = "STEREO_.*";
  o.exclude = "STEREO_PREVIEW";
  Recorder recorder(o);
  const auto blob = numbered_bytes(100, 1);
  for (const char* channel : {"STEREO_IMAGES", "STEREO_PREVIEW", "DEPTH_IMAGE", "X_STEREO_IMAGES"})
    offer(recorder, channel, blob);
  offer(recorder, "RIG_CALIBRATION", calibration_payload(1));
  ASSERT_TRUE(recorder.finish());
  EXPECT_EQ(recorder.status().received, 2);
  const auto r = read_back(dir.file("rec.lcmlog"));
  ASSERT_EQ(r.events.size(), 2u);
  EXPECT_EQ(r.events[0].channel, "STEREO_IMAGES");
  EXPECT_EQ(r.events[1].channel, "RIG_CALIBRATION");
}

TEST(Recorder, SplitFilesEachStartWithTheNewestCalibration) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir, "split.lcmlog");
  o.log.split_bytes = 5'000'000;
  Recorder recorder(o);
  const auto first = calibration_payload(1), second = calibration_payload(2);
  const auto blob = numbered_bytes(1'000'000, 7);
  offer(recorder, "RIG_CALIBRATION", first);
  for (int i = 0; i < 12; ++i) offer(recorder, "BLOB", blob);
  offer(recorder, "RIG_CALIBRATION", second);
  for (int i = 0; i < 12; ++i) offer(recorder, "BLOB", blob);
  ASSERT_TRUE(recorder.finish());

  const auto& files = recorder.files();
  ASSERT_GE(files.size(), 5u);
  EXPECT_EQ(files[0], dir.file("split.lcmlog.00"));
  EXPECT_EQ(files[1], dir.file("split.lcmlog.01"));
  int blobs = 0;
  bool second_seen = false;
  for (const auto& path : files) {
    EXPECT_LE(std::filesystem::file_size(path), o.log.split_bytes) << path;
    const auto r = read_back(path);
    ASSERT_TRUE(r.problems.empty()) << path;
    ASSERT_FALSE(r.events.empty()) << path;
    EXPECT_EQ(r.events[0].channel, "RIG_CALIBRATION") << path;
    EXPECT_EQ(r.events[0].data, second_seen ? second : first) << path;
    for (const auto& e : r.events) {
      blobs += e.channel == "BLOB";
      second_seen = second_seen || (e.channel == "RIG_CALIBRATION" && e.data == second);
    }
    EXPECT_NE(read_file(sidecar_path(path)).find("\"starts_with_calibration\": true"), std::string::npos) << path;
  }
  EXPECT_TRUE(second_seen);
  EXPECT_EQ(blobs, 24);
  EXPECT_EQ(recorder.status().written, 26);  // the copies are not counted as received messages
}

// The pmd files start the logger seconds before the drivers; the processes'
// heartbeats arrive meanwhile. "No calibration" is said only once data other
// than heartbeats has gone without one for calibration_warning_s. Heartbeats
// are known by their type, on whatever --status-channel they came.
TEST(Recorder, WarnsOfNoCalibrationOnlyOnceDataCameWithoutOne) {
  test::TempDir dir;
  RecorderOptions options = options_in(dir);
  options.calibration_warning_s = 0.05;
  Recorder recorder(options);
  offer(recorder, "PROCESS_STATUS", heartbeat_payload("depth_monitor"));
  offer(recorder, "ROBOT_B_STATUS", heartbeat_payload("stereo_detector"));
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // past the limit, not a timing check
  EXPECT_EQ(recorder.check_health(), "recording") << "only heartbeats so far";
  offer(recorder, "STEREO_IMAGES", numbered_bytes(1000, 2));
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  EXPECT_EQ(recorder.check_health(), "recording, no RIG_CALIBRATION");
  ASSERT_TRUE(recorder.finish());
}

// A logger killed outright never closes its file: the sidecar, refreshed as
// it writes, still says what the file held (here after every event).
TEST(Recorder, SidecarFollowsTheFileWhileItIsWritten) {
  test::TempDir dir;
  RecorderOptions options = options_in(dir);
  options.log.sidecar_refresh_s = 0;
  Recorder recorder(options);
  offer(recorder, "RIG_CALIBRATION", calibration_payload(5), 10);
  offer(recorder, "STEREO_IMAGES", numbered_bytes(1000, 1), 11);
  offer(recorder, "STEREO_IMAGES", numbered_bytes(1000, 2), 12);
  for (int i = 0; i < 500 && recorder.status().written < 3; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // bounded wait for the writer thread
  ASSERT_EQ(recorder.status().written, 3);
  const std::string sidecar = read_file(sidecar_path(dir.file("rec.lcmlog")));
  EXPECT_NE(sidecar.find("\"complete\": false"), std::string::npos) << sidecar;
  EXPECT_NE(sidecar.find("\"events\": 3"), std::string::npos) << sidecar;
  EXPECT_FALSE(std::filesystem::exists(sidecar_path(dir.file("rec.lcmlog")) + ".tmp"));
  ASSERT_TRUE(recorder.finish());
  EXPECT_NE(read_file(sidecar_path(dir.file("rec.lcmlog"))).find("\"complete\": true"), std::string::npos);
}

TEST(Recorder, FinishWritesOutEverythingQueued) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir);
  o.max_write_bytes_per_s = 20e6;  // 20 MB take at least a second: a backlog builds up
  Recorder recorder(o);
  const auto blob = numbered_bytes(1'000'000, 3);
  for (int i = 0; i < 20; ++i) offer(recorder, "BLOB", blob);
  EXPECT_GT(recorder.status().queue_depth, 0);
  ASSERT_TRUE(recorder.finish());
  const RecorderStatus s = recorder.status();
  EXPECT_EQ(s.received, 20);
  EXPECT_EQ(s.written, 20);
  EXPECT_EQ(s.queue_depth, 0);
  EXPECT_EQ(read_back(dir.file("rec.lcmlog")).events.size(), 20u);
}

// A stop does not wait for the write cap: at 1 kB/s the 5 MB queued here
// would take over an hour.
TEST(Recorder, FinishLiftsTheWriteCap) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir);
  o.max_write_bytes_per_s = 1000;
  Recorder recorder(o);
  const auto blob = numbered_bytes(1'000'000, 3);
  for (int i = 0; i < 5; ++i) offer(recorder, "BLOB", blob);
  auto finished = std::async(std::launch::async, [&] { return recorder.finish(); });
  ASSERT_EQ(finished.wait_for(std::chrono::seconds(120)), std::future_status::ready)
      << "finish() still throttled to 1 kB/s";
  EXPECT_TRUE(finished.get());
  EXPECT_EQ(recorder.status().written, 5);
}

TEST(Recorder, MessagesRefusedByAFullQueueAreCounted) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir);
  o.max_queue_bytes = 250'000;
  o.max_write_bytes_per_s = 2e6;  // 0.05 s per message: far slower than offering them
  Recorder recorder(o);
  const auto blob = numbered_bytes(100'000, 3);
  for (int i = 0; i < 10; ++i) offer(recorder, "BLOB", blob);
  EXPECT_FALSE(recorder.finish());
  const RecorderStatus s = recorder.status();
  EXPECT_GT(s.dropped, 0);
  EXPECT_EQ(s.dropped_bytes, s.dropped * 100'000);
  EXPECT_EQ(s.received, s.written + s.dropped);
  EXPECT_EQ(static_cast<int64_t>(read_back(dir.file("rec.lcmlog")).events.size()), s.written);
  EXPECT_NE(read_file(sidecar_path(dir.file("rec.lcmlog"))).find("\"dropped\": " + std::to_string(s.dropped)),
            std::string::npos);
}

TEST(Recorder, AWriteErrorLeavesAReadableLogAndSaysWhy) {
  test::TempDir dir;
  const std::string path = dir.file("rec.lcmlog");
  Recorder recorder(options_in(dir));
  const auto blob = numbered_bytes(1'000'000, 5);
  {
    test::FileSizeLimit limit(3'500'000);
    for (int i = 0; i < 10; ++i) offer(recorder, "BLOB", blob);
    EXPECT_FALSE(recorder.finish());
  }
  const RecorderStatus s = recorder.status();
  EXPECT_TRUE(s.failed);
  EXPECT_TRUE(recorder.failed());
  EXPECT_NE(s.error.find(std::strerror(EFBIG)), std::string::npos) << s.error;
  EXPECT_EQ(s.written, 3);
  EXPECT_EQ(s.unwritten, 7);
  const auto r = read_back(path);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.events.size(), 3u);
  const std::string sidecar = read_file(sidecar_path(path));
  EXPECT_NE(sidecar.find("\"complete\": false"), std::string::npos) << sidecar;
  EXPECT_NE(sidecar.find(std::strerror(EFBIG)), std::string::npos) << sidecar;
}

TEST(Recorder, StopsShortOfFillingTheDiskWithAWholeLog) {
  test::TempDir dir;
  const std::string path = dir.file("rec.lcmlog");
  RecorderOptions o = options_in(dir);
  std::atomic<uint64_t> free{5'000'000'000};
  o.disk_reserve = {2'000'000'000, 0.0, [&] { return std::optional<uint64_t>(free.load()); }};
  Recorder recorder(o);
  const auto blob = numbered_bytes(1000, 3);
  for (int i = 0; i < 3; ++i) offer(recorder, "BLOB", blob);
  // bounded wait for the writer: the three are on disk before the disk fills
  for (int i = 0; i < 2000 && recorder.status().written < 3; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  free = 1'500'000'000;
  for (int i = 0; i < 4; ++i) offer(recorder, "BLOB", blob);
  EXPECT_FALSE(recorder.finish());
  const RecorderStatus s = recorder.status();
  EXPECT_TRUE(s.failed);
  EXPECT_EQ(s.written, 3);
  EXPECT_EQ(s.unwritten, 4);
  EXPECT_NE(s.error.find("only 1500 MB free on the disk of " + path +
                         ": the next 1004-byte event would leave less than --min-free-mb 2000"),
            std::string::npos)
      << s.error;
  const auto r = read_back(path);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.events.size(), 3u);
  EXPECT_NE(read_file(sidecar_path(path)).find("--min-free-mb"), std::string::npos);
}

TEST(Recorder, RefusesToStartWithoutRoomAndCreatesNoFile) {
  test::TempDir dir;
  RecorderOptions o = options_in(dir);
  // Room for the reserve but not a quarter more: a logger respawned now
  // would stop again at once.
  o.disk_reserve = {2'000'000'000, 1.0, [] { return std::optional<uint64_t>(2'499'999'999); }};
  try {
    Recorder refused(o);
    ADD_FAILURE() << "started with too little room";
  } catch (const logio::LogWriteError& e) {
    EXPECT_NE(std::string(e.what()).find("only 2499 MB free on the disk of " + o.log.path +
                                         ", under the 2500 MB a start needs (--min-free-mb 2000"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(o.log.path));
  o.disk_reserve.free_bytes = [] { return std::optional<uint64_t>(2'500'000'000); };
  EXPECT_NO_THROW(Recorder{o});
  std::filesystem::remove(o.log.path);
  // No reserve, or a disk that cannot say how full it is: recording goes on.
  o.disk_reserve.min_free_bytes = 0;
  EXPECT_NO_THROW(Recorder{o});
  RecorderOptions unknown = options_in(dir, "other.lcmlog");
  unknown.disk_reserve = {2'000'000'000, 1.0, [] { return std::optional<uint64_t>(); }};
  EXPECT_NO_THROW(Recorder{unknown});
}

TEST(DiskReserve, LooksOncePeriodOrAQuarterOfTheReserveWrittenOrWhenTheNextEventMightNotFit) {
  int looks = 0;
  uint64_t free = 10'000;
  DiskReserve reserve("/x/rec.lcmlog", {1000, 10.0, [&] {
                                          ++looks;
                                          return std::optional<uint64_t>(free);
                                        }});
  EXPECT_EQ(looks, 1);
  const double t0 = monotonic_ms();
  reserve.check(t0 + 1, 100, 10);
  EXPECT_EQ(looks, 1) << "nothing due yet";
  reserve.check(t0 + 1, 250, 10);
  EXPECT_EQ(looks, 2) << "a quarter of the reserve written";
  reserve.check(t0 + 20'000, 260, 10);
  EXPECT_EQ(looks, 3) << "the period passed";
  // 10000 free at the last look and 8700 written since: 400 more might leave
  // 900, so it looks again; the disk now says 1300, which does not hold them
  free = 1300;
  EXPECT_THROW(reserve.check(t0 + 20'001, 260 + 8700, 400), logio::LogWriteError);
  EXPECT_EQ(looks, 4) << "looked again before refusing";
  EXPECT_EQ(reserve.last_free_bytes(), 1300u);
  EXPECT_NO_THROW(reserve.check(t0 + 20'002, 260 + 8700, 300)) << "1300 holds 300 and the 1000";
  // A disk that cannot say how full it is: nothing to go by.
  DiskReserve blind("/x/rec.lcmlog", {1000, 0.0, [] { return std::optional<uint64_t>(); }});
  EXPECT_NO_THROW(blind.check(t0, 1'000'000, 1'000'000));
}

}  // namespace
}  // namespace ivoa::logger
