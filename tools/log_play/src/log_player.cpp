#include "ivoa/log_play/log_player.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/logio/channel_filter.hpp"
#include "ivoa/logio/log_reader.hpp"

namespace ivoa::log_play {

double due_ms(int64_t timestamp_us, int64_t first_timestamp_us, double speed) {
  if (speed <= 0) return 0;
  return static_cast<double>(std::max<int64_t>(0, timestamp_us - first_timestamp_us)) / 1000.0 / speed;
}

// The stream's clock across files: the first event's log time and the wall
// time play began, and the latest log time played (log time never runs back).
struct LogPlayer::Pacing {
  bool started = false;
  int64_t first_us = 0, latest_us = 0;
  double start_ms = 0;
};

LogPlayer::LogPlayer(Bus& bus, Heartbeat& heartbeat, std::vector<std::string> paths, LogPlayerOptions options)
    : bus_(bus),
      heartbeat_(heartbeat),
      options_(std::move(options)),
      filter_(std::make_unique<logio::ChannelFilter>(options_.channels, options_.exclude)) {
  for (auto& path : paths) readers_.push_back(std::make_unique<logio::LogReader>(path, logio::LogReaderOptions{true}));
  heartbeat_.set_counter("files_done", 0);
  heartbeat_.set_counter("filtered_out", 0);
  heartbeat_.set_state(fmt::format("ready to play {} file(s)", readers_.size()));
}

LogPlayer::~LogPlayer() = default;

bool LogPlayer::play() {
  Pacing pacing;
  for (size_t i = 0; i < readers_.size(); ++i) {
    heartbeat_.set_state(fmt::format("playing {} ({} of {})", readers_[i]->path(), i + 1, readers_.size()));
    heartbeat_.publish_now();
    const bool whole = play_file(*readers_[i], pacing);
    report_problems(*readers_[i]);
    if (!whole) return false;
    heartbeat_.set_counter("files_done", ++counts_.files_done);
  }
  heartbeat_.set_state("finished");
  return true;
}

bool LogPlayer::play_file(logio::LogReader& reader, Pacing& pacing) {
  logio::LogEvent event;
  while (reader.next(event)) {
    if (!filter_->accepts(event.channel)) {
      heartbeat_.set_counter("filtered_out", ++counts_.filtered_out);
      continue;
    }
    if (!pacing.started) {
      pacing.started = true;
      pacing.first_us = pacing.latest_us = event.timestamp;
      pacing.start_ms = monotonic_ms();
    }
    pacing.latest_us = std::max(pacing.latest_us, event.timestamp);
    if (!wait_until(pacing.start_ms + due_ms(pacing.latest_us, pacing.first_us, options_.speed))) return false;
    if (bus_.publish_raw(event.channel, event.data.data(), event.data.size())) {
      ++counts_.published;
      heartbeat_.count_out();
    } else {
      ++counts_.publish_failures;
      heartbeat_.add_to_counter("publish_failures", 1);
    }
    heartbeat_.tick();
    if (stop_requested()) return false;
  }
  return true;
}

// Sleeps in short steps, so a stop and the heartbeat are not held up by a
// long pause in the log. False if a stop was requested meanwhile.
bool LogPlayer::wait_until(double due) {
  while (!stop_requested()) {
    const double left = due - monotonic_ms();
    if (left <= 0) return true;
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(std::min(left, 50.0)));
    heartbeat_.tick();
  }
  return false;
}

void LogPlayer::report_problems(const logio::LogReader& reader) {
  for (const auto& problem : reader.problems()) {
    ++counts_.damaged;
    heartbeat_.bad_input(reader.path() + ": " + problem.describe());
  }
  if (const std::string not_a_log = reader.not_a_log(); !not_a_log.empty()) {
    ++counts_.not_logs;
    spdlog::error("{}: {}", reader.path(), not_a_log);
  } else if (reader.size() == 0) {  // an empty log is a log, but there is nothing to play in it
    ++counts_.not_logs;
    heartbeat_.bad_input(reader.path() + ": an empty file: no event to play");
  }
}

}  // namespace ivoa::log_play
