// libs/logio: the writer's files are standard LCM logs (lcm::LogFile reads
// them and the reader reads lcm::LogFile's), damage is reported at its byte
// offset with every good event before it kept, and a refused write leaves
// a file that ends with its last whole event.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <lcm/lcm-cpp.hpp>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/logio/log_format.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/log_summary.hpp"
#include "ivoa/logio/log_writer.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/logio/session_name.hpp"
#include "ivoa/process_status_t.hpp"
#include "logger_test_util.hpp"
#include "test_rig.hpp"

namespace ivoa::logio {
namespace {

using test::numbered_bytes;
using test::read_back;

// Writes `n` events of `size` bytes on channel "CH<i>"; returns each event's offset.
std::vector<uint64_t> write_log(const std::string& path, int n, size_t size) {
  LogWriter writer(path);
  std::vector<uint64_t> offsets;
  for (int i = 0; i < n; ++i) {
    offsets.push_back(writer.bytes());
    const auto data = numbered_bytes(size, static_cast<uint8_t>(i));
    writer.write("CH" + std::to_string(i), 1000 + i, data.data(), data.size());
  }
  writer.close();
  return offsets;
}

void overwrite_byte(const std::string& path, uint64_t offset, char value) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.put(value);
}

TEST(LogWriter, LcmLogFileReadsWhatItWrites) {
  test::TempDir dir;
  const std::string path = dir.file("w.lcmlog");
  write_log(path, 4, 3000);
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  for (int i = 0; i < 4; ++i) {
    const lcm::LogEvent* e = log.readNextEvent();
    ASSERT_NE(e, nullptr) << "event " << i;
    EXPECT_EQ(e->eventnum, i);
    EXPECT_EQ(e->timestamp, 1000 + i);
    EXPECT_EQ(e->channel, "CH" + std::to_string(i));
    const auto expected = numbered_bytes(3000, static_cast<uint8_t>(i));
    ASSERT_EQ(e->datalen, 3000);
    EXPECT_EQ(0, std::memcmp(e->data, expected.data(), expected.size()));
  }
  EXPECT_EQ(log.readNextEvent(), nullptr);
}

TEST(LogReader, ReadsWhatLcmLogFileWrote) {
  test::TempDir dir;
  const std::string path = dir.file("lcm.lcmlog");
  {
    lcm::LogFile log(path, "w");
    for (int i = 0; i < 3; ++i) {
      auto data = numbered_bytes(100 + static_cast<size_t>(i), static_cast<uint8_t>(i));
      lcm::LogEvent e{};
      e.timestamp = 50 + i;
      e.channel = "LCM_" + std::to_string(i);
      e.datalen = static_cast<int32_t>(data.size());
      e.data = data.data();
      ASSERT_EQ(log.writeEvent(&e), 0);
    }
  }
  const auto r = read_back(path);
  ASSERT_TRUE(r.problems.empty());
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_EQ(r.events[2].channel, "LCM_2");
  EXPECT_EQ(r.events[2].timestamp, 52);
  EXPECT_EQ(r.events[2].event_number, 2);
  EXPECT_EQ(r.events[2].data, numbered_bytes(102, 2));

  LogReader headers(path, {/*resync=*/false, /*headers_only=*/true});
  LogEvent event;
  std::vector<std::string> channels;
  while (headers.next(event)) {
    channels.push_back(event.channel);
    EXPECT_TRUE(event.data.empty()) << "headers only";
  }
  EXPECT_TRUE(headers.clean());
  EXPECT_EQ(channels, (std::vector<std::string>{"LCM_0", "LCM_1", "LCM_2"}));
  EXPECT_EQ(event.timestamp, 52);
}

TEST(LogWriter, RefusesAnExistingFileUnlessAskedToOverwrite) {
  test::TempDir dir;
  const std::string path = dir.file("exists.lcmlog");
  write_log(path, 1, 10);
  EXPECT_THROW(LogWriter{path}, LogWriteError);
  LogWriterOptions overwrite;
  overwrite.overwrite = true;
  LogWriter writer(path, overwrite);
  writer.close();
  EXPECT_EQ(std::filesystem::file_size(path), 0u);
}

// Two loggers started with --force on one file: the second emptied the
// first one's recording and wrote over it, and both reported success.
TEST(LogWriter, AFileAnotherWriterHoldsIsRefusedEvenWhenOverwriting) {
  test::TempDir dir;
  const std::string path = dir.file("busy.lcmlog");
  LogWriter first(path);
  const uint8_t payload[4] = {1, 2, 3, 4};
  first.write("FIRST", 1, payload, sizeof payload);
  LogWriterOptions overwrite;
  overwrite.overwrite = true;
  try {
    LogWriter second(path, overwrite);
    FAIL() << "a second writer took a file being written";
  } catch (const LogWriteError& e) {
    EXPECT_NE(std::string(e.what()).find("another process is writing it"), std::string::npos) << e.what();
  }
  first.write("FIRST", 2, payload, sizeof payload);
  first.close();
  LogReader reader(path);
  LogEvent event;
  int events = 0;
  while (reader.next(event)) ++events;
  EXPECT_EQ(events, 2);
  EXPECT_TRUE(reader.clean());
  LogWriter after(path, overwrite);  // once closed, it may be overwritten
  after.close();
  EXPECT_EQ(std::filesystem::file_size(path), 0u);
}

// A folder given as the log: "use --force" would not help, so it is not offered.
TEST(LogWriter, FolderIsRefusedAsSuchWithOrWithoutOverwrite) {
  test::TempDir dir;
  LogWriterOptions overwrite;
  overwrite.overwrite = true;
  for (const LogWriterOptions& options : {LogWriterOptions{}, overwrite}) {
    try {
      LogWriter writer(dir.path().string(), options);
      FAIL() << "opened a folder as a log";
    } catch (const LogWriteError& e) {
      EXPECT_NE(std::string(e.what()).find("it is a folder (name a file in it)"), std::string::npos) << e.what();
    }
  }
}

// A pipe (`ivoa-log-check <(cat log)`) or a device read as a file of size 0:
// "intact but empty", exit 0.
TEST(LogReader, APipeOrDeviceIsRefusedAsNotARegularFile) {
  try {
    LogReader reader("/dev/null");
    FAIL() << "read a device as a log";
  } catch (const LogReadError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null: not a regular file"), std::string::npos) << e.what();
  }
}

TEST(LogReader, TruncatedEventIsReportedAtItsOffsetAfterTheGoodOnes) {
  test::TempDir dir;
  const std::string path = dir.file("cut.lcmlog");
  const auto offsets = write_log(path, 5, 1000);
  std::filesystem::resize_file(path, offsets[3] + 500);  // inside event 3's message
  const auto r = read_back(path);
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_EQ(r.events[2].data, numbered_bytes(1000, 2));
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].offset, offsets[3]);
  EXPECT_NE(r.problems[0].what.find("truncated"), std::string::npos) << r.problems[0].what;
  EXPECT_NE(r.problems[0].describe().find("byte " + std::to_string(offsets[3])), std::string::npos);
  EXPECT_TRUE(r.problems[0].cut_short && r.problems[0].to_end);
}

TEST(LogReader, EndInsideAnEventHeaderIsReported) {
  test::TempDir dir;
  const std::string path = dir.file("cut_header.lcmlog");
  const auto offsets = write_log(path, 3, 100);
  std::filesystem::resize_file(path, offsets[2] + 10);
  const auto r = read_back(path);
  EXPECT_EQ(r.events.size(), 2u);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].offset, offsets[2]);
  EXPECT_NE(r.problems[0].what.find("10 bytes into an event header"), std::string::npos) << r.problems[0].what;
  EXPECT_TRUE(r.problems[0].cut_short);
}

TEST(LogReader, CorruptEventStopsReadingThereByDefault) {
  test::TempDir dir;
  const std::string path = dir.file("bad_sync.lcmlog");
  const auto offsets = write_log(path, 4, 200);
  overwrite_byte(path, offsets[1], 0x00);  // event 1's sync word
  const auto r = read_back(path);
  EXPECT_EQ(r.events.size(), 1u);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].offset, offsets[1]);
  EXPECT_NE(r.problems[0].what.find("sync word"), std::string::npos) << r.problems[0].what;
  EXPECT_FALSE(r.problems[0].cut_short);
}

TEST(LogReader, ResyncSkipsOnlyTheDamagedEvent) {
  test::TempDir dir;
  const std::string path = dir.file("bad_length.lcmlog");
  const auto offsets = write_log(path, 4, 200);
  overwrite_byte(path, offsets[1] + 20, 0x7F);  // event 1's channel length, now absurd
  const auto r = read_back(path, /*resync=*/true);
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_EQ(r.events[1].channel, "CH2");
  EXPECT_EQ(r.events[1].offset, offsets[2]);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].offset, offsets[1]);
  EXPECT_EQ(r.problems[0].skipped_bytes, offsets[2] - offsets[1]);
  EXPECT_NE(r.problems[0].what.find("channel name length"), std::string::npos) << r.problems[0].what;
}

// Reads `path` to the end with default options; returns not_a_log().
std::string not_a_log(const std::string& path, bool resync = false) {
  LogReader reader(path, {resync});
  LogEvent e;
  while (reader.next(e)) {
  }
  return reader.not_a_log();
}

TEST(LogReader, SaysAFileIsNotALogOnlyWhenNothingCouldBeReadFromItsStart) {
  test::TempDir dir;
  const std::string text = dir.file("notes.lcmlog");
  std::ofstream(text) << "notes, not a log: long enough to hold an event header\n";
  EXPECT_NE(not_a_log(text).find("not an LCM log, or damaged from its start (byte 0: "), std::string::npos)
      << not_a_log(text);

  const std::string damaged_later = dir.file("later.lcmlog");
  const auto offsets = write_log(damaged_later, 3, 100);
  overwrite_byte(damaged_later, offsets[1], 0x00);
  EXPECT_EQ(not_a_log(damaged_later), "") << "its first event is good";

  const std::string damaged_first = dir.file("first.lcmlog");
  write_log(damaged_first, 3, 100);
  overwrite_byte(damaged_first, 0, 0x00);
  EXPECT_NE(not_a_log(damaged_first), "");
  EXPECT_EQ(not_a_log(damaged_first, /*resync=*/true), "") << "the events after the first are read";

  const std::string empty = dir.file("empty.lcmlog");
  std::ofstream{empty};
  EXPECT_EQ(not_a_log(empty), "") << "an empty log is a log";
}

TEST(LogReader, MissingFileThrowsNamingIt) {
  try {
    LogReader reader("/nonexistent/x.lcmlog");
    FAIL() << "no exception";
  } catch (const LogReadError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.lcmlog"), std::string::npos);
  }
}

TEST(LogWriter, ARefusedWriteLeavesTheFileEndingWithItsLastWholeEvent) {
  test::TempDir dir;
  const std::string path = dir.file("limited.lcmlog");
  const size_t event_size = 1'000'000;
  LogWriter writer(path);
  {
    test::FileSizeLimit limit(2'500'000);  // room for two events and half of a third
    const auto data = numbered_bytes(event_size, 1);
    writer.write("BIG", 1, data.data(), data.size());
    writer.write("BIG", 2, data.data(), data.size());
    try {
      writer.write("BIG", 3, data.data(), data.size());
      FAIL() << "the third write should have failed";
    } catch (const LogWriteError& e) {
      EXPECT_NE(std::string(e.what()).find(std::strerror(EFBIG)), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_THROW(writer.write("BIG", 4, data.data(), 10), LogWriteError);
  }
  writer.close();
  EXPECT_EQ(writer.events(), 2);
  EXPECT_EQ(std::filesystem::file_size(path), writer.bytes());
  const auto r = read_back(path);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.events.size(), 2u);
  lcm::LogFile log(path, "r");
  int lcm_events = 0;
  while (log.readNextEvent() != nullptr) ++lcm_events;
  EXPECT_EQ(lcm_events, 2);
}

// A recording that stopped while writing its last event (a logger killed,
// a power cut) loses only that event: LCM's reader, which processes
// replaying a log go through, plays every event before it and ends there,
// so such a log is played with a warning. Any other damage is refused.
TEST(ReplayCheck, OnlyALastEventCutShortIsPlayedAndWithAWarning) {
  test::TempDir dir;
  const std::string cut = dir.file("cut.lcmlog");
  for (const uint64_t into_last : {300, 2, 20}) {  // bytes into the last event: its data, sync word, header
    std::filesystem::remove(cut);
    const auto offsets = write_log(cut, 4, 500);
    const uint64_t size = offsets[3] + into_last;
    std::filesystem::resize_file(cut, size);
    const ReplayCheck check = check_log_for_replay("file://" + cut + "?speed=0");
    EXPECT_EQ(check.refusal, "") << "cut at " << size;
    EXPECT_NE(check.warning.find(cut + ": its last event, at byte " + std::to_string(offsets[3]) +
                                 ", is cut short (truncated: "),
              std::string::npos)
        << check.warning;
    EXPECT_NE(check.warning.find("the recording stopped while writing it. The 3 events before it are played"),
              std::string::npos)
        << check.warning;
    lcm::LogFile log(cut, "r");
    int lcm_events = 0;
    while (log.readNextEvent() != nullptr) ++lcm_events;
    EXPECT_EQ(lcm_events, 3) << "LCM's reader plays up to the cut";
  }
  EXPECT_NO_THROW(refuse_a_log_lcm_cannot_replay("file://" + cut));

  const std::string whole = dir.file("whole.lcmlog");
  write_log(whole, 2, 100);
  const ReplayCheck whole_check = check_log_for_replay("file://" + whole);
  EXPECT_EQ(whole_check.refusal + whole_check.warning, "");

  const std::string garbage_tail = dir.file("garbage_tail.lcmlog");
  write_log(garbage_tail, 2, 100);
  std::ofstream(garbage_tail, std::ios::app) << "xyz";  // bytes that start no event
  EXPECT_NE(check_log_for_replay("file://" + garbage_tail).refusal.find("damaged at byte"), std::string::npos);

  const std::string damaged_before_cut = dir.file("two_problems.lcmlog");
  const auto at = write_log(damaged_before_cut, 4, 500);
  overwrite_byte(damaged_before_cut, at[1], 0x00);
  std::filesystem::resize_file(damaged_before_cut, at[3] + 300);
  const ReplayCheck two = check_log_for_replay("file://" + damaged_before_cut);
  EXPECT_NE(two.refusal.find("damaged at byte " + std::to_string(at[1])), std::string::npos) << two.refusal;
  EXPECT_THROW(refuse_a_log_lcm_cannot_replay("file://" + damaged_before_cut), BusError);

  const std::string absurd_tail = dir.file("absurd_tail.lcmlog");  // the header that crashed LCM's reader
  write_log(absurd_tail, 2, 100);
  EventHeader absurd;
  absurd.channel_bytes = 2;
  absurd.data_bytes = 0x7FFFFFFF;
  const auto head = encode_header(absurd);
  std::ofstream(absurd_tail, std::ios::app | std::ios::binary)
      .write(reinterpret_cast<const char*>(head.data()), static_cast<std::streamsize>(head.size()));
  EXPECT_NE(check_log_for_replay("file://" + absurd_tail).refusal.find("message length"), std::string::npos);
}

std::vector<uint8_t> encoded_stereo(int64_t seq, int64_t utime) {
  stereo_image_t msg;
  msg.utime = utime;
  msg.seq = seq;
  set_counts(msg);
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

TEST(LogSummary, CountsSequenceGapsRepeatsAndUtimeRegressions) {
  LogSummary summary;
  for (const int64_t seq : {0, 1, 2, 5, 6, 6, 9}) {
    const auto bytes = encoded_stereo(seq, seq == 9 ? 1 : 100 + seq);
    summary.add("STEREO_IMAGES", 7, bytes.data(), bytes.size());
  }
  const ChannelSummary& s = summary.channels().at("STEREO_IMAGES");
  EXPECT_EQ(s.type, "ivoa.stereo_image_t");
  EXPECT_EQ(s.count, 7);
  EXPECT_EQ(s.first_seq, 0);
  EXPECT_EQ(s.last_seq, 9);
  EXPECT_EQ(s.missing_seq, 4);  // 3, 4, 7, 8
  ASSERT_EQ(s.gaps.size(), 2u);
  EXPECT_EQ(s.gaps[0].after, 2);
  EXPECT_EQ(s.gaps[0].next, 5);
  EXPECT_EQ(s.seq_regressions, 1);
  EXPECT_EQ(s.utime_regressions, 1);
}

// A respawned driver numbers its frames from 0 again, later in time: that
// run lost nothing but its own first numbers, and the table says the
// numbers started again. A repeat or a late message is not a restart.
ChannelSummary summary_of(const std::vector<std::pair<int64_t, int64_t>>& seq_and_utime, std::string* table = nullptr) {
  LogSummary summary;
  for (const auto& [seq, utime] : seq_and_utime) {
    const auto bytes = encoded_stereo(seq, utime);
    summary.add("STEREO_IMAGES", 7, bytes.data(), bytes.size());
  }
  if (table) *table = summary.table();
  return summary.channels().at("STEREO_IMAGES");
}

TEST(LogSummary, APublisherThatStartsAgainIsARestartNotARegression) {
  std::string table;
  ChannelSummary s = summary_of({{0, 100}, {1, 101}, {2, 102}, {0, 200}, {1, 201}, {3, 203}, {3, 203}}, &table);
  EXPECT_EQ(s.seq_restarts, 1);
  EXPECT_EQ(s.seq_regressions, 1) << "3 again, at its own utime";
  EXPECT_EQ(s.missing_seq, 1) << "2 of the second run";
  EXPECT_NE(
      table.find("STEREO_IMAGES: its sequence started again 1 time (went back as time went on: a publisher restarted)"),
      std::string::npos)
      << table;
  EXPECT_NE(table.find("STEREO_IMAGES: 1 message repeated or out of order"), std::string::npos) << table;
  EXPECT_NE(channel_json(s).find("\"seq_restarts\": 1"), std::string::npos);

  s = summary_of({{5, 100}, {6, 101}, {1, 300}, {2, 301}});  // the new run's 0 lost
  EXPECT_EQ(s.seq_restarts, 1);
  EXPECT_EQ(s.seq_regressions, 0);
  EXPECT_EQ(s.missing_seq, 1);
  s = summary_of({{0, 100}, {0, 300}});  // one message, then a respawn
  EXPECT_EQ(s.seq_restarts, 1);
  EXPECT_EQ(s.seq_regressions, 0);
  s = summary_of({{1, 101}, {0, 100}, {2, 102}});  // a late message
  EXPECT_EQ(s.seq_restarts, 0);
  EXPECT_EQ(s.seq_regressions, 1);
  EXPECT_EQ(s.missing_seq, 0) << "2 follows 1, the newest";
}

TEST(LogSummary, HeartbeatsOfManySendersAreNotCountedAsUtimeRegressions) {
  LogSummary summary;
  for (const int64_t utime : {200, 100, 300, 250}) {  // two processes' heartbeats, interleaved
    process_status_t status{};                        // value-initialised: the array counts are 0
    status.utime = utime;
    std::vector<uint8_t> bytes(static_cast<size_t>(status.getEncodedSize()));
    status.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    summary.add("PROCESS_STATUS", utime, bytes.data(), bytes.size());
  }
  const ChannelSummary& s = summary.channels().at("PROCESS_STATUS");
  EXPECT_EQ(s.type, "ivoa.process_status_t");
  EXPECT_FALSE(s.utime_ordered);
  EXPECT_EQ(s.utime_regressions, 0);
  EXPECT_EQ(channel_json(s).find("utime_regressions"), std::string::npos);
  const std::string table = summary.table();
  const size_t start = table.find("PROCESS_STATUS");
  const std::string row = table.substr(start, table.find('\n', start) - start);
  EXPECT_EQ(row.back(), '-') << "the utime< column: " << row;
}

TEST(LogSummary, UnknownPayloadsAreCountedButNotDecoded) {
  LogSummary summary;
  const auto blob = numbered_bytes(64, 3);
  summary.add("FOREIGN", 1, blob.data(), blob.size());
  summary.add("FOREIGN", 2, blob.data(), 3);  // shorter than a fingerprint
  const auto other = numbered_bytes(16, 9);   // another foreign "fingerprint"
  summary.add("FOREIGN", 3, other.data(), other.size());
  const ChannelSummary& s = summary.channels().at("FOREIGN");
  EXPECT_EQ(s.type, "unknown");
  EXPECT_EQ(s.count, 3);
  EXPECT_EQ(s.bytes, 83u);
  EXPECT_FALSE(s.has_seq);
  // All of another program's alike: the table said "2 of its 3 messages are not unknown".
  EXPECT_EQ(s.other_fingerprints, 0);
  EXPECT_EQ(summary.table().find("are not"), std::string::npos) << summary.table();
  EXPECT_NE(channel_json(s).find("\"type\": \"unknown\""), std::string::npos);
}

// A channel whose first message is of no ivoa type takes the first ivoa
// type after it; what was counted of the first is not counted as that type.
TEST(LogSummary, AChannelWhoseFirstMessageIsDamagedCountsItsTypeFromTheNext) {
  LogSummary summary;
  const auto blob = numbered_bytes(64, 3);
  summary.add("STEREO_IMAGES", 1, blob.data(), blob.size());
  for (const int64_t seq : {5, 6, 7}) {
    const auto bytes = encoded_stereo(seq, 100 + seq);
    summary.add("STEREO_IMAGES", 2, bytes.data(), bytes.size());
  }
  const ChannelSummary& s = summary.channels().at("STEREO_IMAGES");
  EXPECT_EQ(s.type, "ivoa.stereo_image_t");
  EXPECT_EQ(s.count, 4);
  EXPECT_EQ(s.typed, 3) << "--expect STEREO_IMAGES=3 holds";
  EXPECT_EQ(s.other_fingerprints, 1);
  EXPECT_EQ(s.first_seq, 5);
  EXPECT_EQ(s.missing_seq, 0);
  EXPECT_EQ(s.first_utime, 105);
}

// Named by type; a channel's 255-byte name keeps its row whole.
TEST(LogSummary, MessagesOfAnotherTypeOnAChannelAreSaidUnderTheTable) {
  LogSummary summary;
  const auto stereo = encoded_stereo(0, 100);
  summary.add("STEREO_IMAGES", 1, stereo.data(), stereo.size());
  const auto blob = numbered_bytes(64, 3);
  summary.add("STEREO_IMAGES", 2, blob.data(), blob.size());
  depth_image_t depth{};
  set_counts(depth);
  std::vector<uint8_t> depth_bytes(static_cast<size_t>(depth.getEncodedSize()));
  depth.encode(depth_bytes.data(), 0, static_cast<int>(depth_bytes.size()));
  summary.add("STEREO_IMAGES", 3, depth_bytes.data(), depth_bytes.size());
  EXPECT_NE(
      summary.table().find("STEREO_IMAGES: 2 of its 3 messages are not ivoa.stereo_image_t (1 ivoa.depth_image_t, "
                           "1 no ivoa type: another program's, or damaged before the fingerprint)"),
      std::string::npos)
      << summary.table();
  EXPECT_EQ(summary.channels().at("STEREO_IMAGES").typed, 1);
  const std::string long_name(255, 'C');
  summary.add(long_name, 4, stereo.data(), stereo.size());
  EXPECT_NE(summary.table().find(long_name + " ivoa.stereo_image_t"), std::string::npos);
  EXPECT_NE(summary.table().find("\nSTEREO_IMAGES "), std::string::npos) << "the next row starts on its own line";
}

}  // namespace
}  // namespace ivoa::logio

// Split parts read out of order make time go back; the tools that take a
// session's parts (log-check, log-play, dataset) say which to give first.
TEST(SplitParts, OutOfOrderPartsOfOneRecordingAreNamed) {
  using ivoa::logio::split_parts_out_of_order;
  EXPECT_EQ(split_parts_out_of_order({"s.lcmlog.01", "s.lcmlog.00"}), "s.lcmlog.00 before s.lcmlog.01");
  EXPECT_EQ(split_parts_out_of_order({"a/s.lcmlog.00", "a/s.lcmlog.02", "./a/s.lcmlog.01"}),
            "./a/s.lcmlog.01 before a/s.lcmlog.02");
  EXPECT_EQ(split_parts_out_of_order({"s.lcmlog.00", "s.lcmlog.01", "s.lcmlog.02"}), "");
  EXPECT_EQ(split_parts_out_of_order({"t.lcmlog.03", "s.lcmlog.00"}), "") << "two recordings";
  EXPECT_EQ(split_parts_out_of_order({"b/s.lcmlog.03", "a/s.lcmlog.00"}), "") << "two folders";
  EXPECT_EQ(split_parts_out_of_order({"s.lcmlog", "s.lcmlog.00"}), "") << "not a part";
}
