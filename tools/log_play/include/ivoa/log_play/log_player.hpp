#pragma once
// Plays recorded LCM logs into a bus as they were recorded. The split files
// of one session (run.lcmlog.00, .01, ...: ivoa-logger --split-mb) play one
// after another as one stream, which lcm-logplayer (one file) cannot do; at
// the recorded pace, a multiple of it, or as fast as possible; channels
// chosen by regex. Damaged stretches are skipped, counted and reported.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ivoa {
class Bus;
class Heartbeat;
}  // namespace ivoa

namespace ivoa::logio {
class ChannelFilter;
struct LogEvent;
class LogReader;
}  // namespace ivoa::logio

namespace ivoa::log_play {

struct LogPlayerOptions {
  double speed = 1.0;           // 2: twice the recorded pace; 0: as fast as possible
  std::string channels = ".*";  // ECMAScript regex matched against the whole channel name
  std::string exclude;          // channels not to play (empty: none)
  double max_gap_s = 10.0;      // a longer pause between log times plays as this long, reported (0: as recorded)
};

struct PlayCounts {
  int64_t published = 0;
  int64_t filtered_out = 0;  // events of channels not chosen
  int64_t damaged = 0;       // damaged stretches skipped (each reported)
  int64_t publish_failures = 0;
  int files_done = 0;
  int not_logs = 0;          // files no event could be read from (played past, reported)
  int shortened_pauses = 0;  // pauses in the log longer than max_gap_s, each reported
};

// The stream's log time as play time: when an event is due, in ms after the
// first was played, is its log time since the first event over the speed,
// less the pauses cut short. A pause longer than max_gap_s (a log time jump:
// a clock set while recording, or logs of two days played as one) plays as
// max_gap_s, so play does not wait silently for days. A log time earlier than
// the latest (a split file starts with a copy of an older calibration) is due
// at once. Everything is due at once for a speed <= 0.
class PlayClock {
 public:
  PlayClock(double speed, double max_gap_s);
  double due_ms(int64_t timestamp_us);
  // The pause the last due_ms() cut short, in log microseconds (0: none).
  uint64_t last_cut_us() const { return last_cut_us_; }

 private:
  double speed_;
  uint64_t max_gap_us_;  // 0: no limit
  bool started_ = false;
  int64_t latest_us_ = 0;                     // the latest log time played: log time never runs back
  uint64_t played_us_ = 0, last_cut_us_ = 0;  // log time played since the first event, pauses cut short
};

class LogPlayer {
 public:
  // Opens every file first, so that a missing or unreadable one stops
  // everything before anything is played: throws logio::LogReadError
  // naming it; std::invalid_argument for a bad regex.
  LogPlayer(Bus& bus, Heartbeat& heartbeat, std::vector<std::string> paths, LogPlayerOptions options);
  ~LogPlayer();
  LogPlayer(const LogPlayer&) = delete;
  LogPlayer& operator=(const LogPlayer&) = delete;

  // Plays to the end of the last file, or until a stop is requested
  // (stop_requested()); true if it reached the end.
  bool play();
  const PlayCounts& counts() const { return counts_; }

 private:
  struct Pacing;
  bool play_file(logio::LogReader& reader, Pacing& pacing);
  void report_cut(const logio::LogReader& reader, const logio::LogEvent& event, uint64_t cut_us);
  bool wait_until(double due_ms);
  void report_problems(const logio::LogReader& reader);

  Bus& bus_;
  Heartbeat& heartbeat_;
  LogPlayerOptions options_;
  std::unique_ptr<logio::ChannelFilter> filter_;
  std::vector<std::unique_ptr<logio::LogReader>> readers_;
  PlayCounts counts_;
};

}  // namespace ivoa::log_play
