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
class LogReader;
}  // namespace ivoa::logio

namespace ivoa::log_play {

struct LogPlayerOptions {
  double speed = 1.0;           // 2: twice the recorded pace; 0: as fast as possible
  std::string channels = ".*";  // ECMAScript regex matched against the whole channel name
  std::string exclude;          // channels not to play (empty: none)
};

struct PlayCounts {
  int64_t published = 0;
  int64_t filtered_out = 0;  // events of channels not chosen
  int64_t damaged = 0;       // damaged stretches skipped (each reported)
  int64_t publish_failures = 0;
  int files_done = 0;
  int not_logs = 0;  // files no event could be read from (played past, reported)
};

// When an event is due, in ms after play began: its log time since the
// first event, divided by the speed. A log time earlier than the previous
// event's (a split file starts with a copy of an older calibration) is due
// at once. 0 for speed <= 0.
double due_ms(int64_t timestamp_us, int64_t first_timestamp_us, double speed);

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
