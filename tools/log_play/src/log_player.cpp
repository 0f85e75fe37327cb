#include "ivoa/log_play/log_player.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
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

PlayClock::PlayClock(double speed, double max_gap_s)
    : speed_(speed), max_gap_us_(max_gap_s > 0 ? static_cast<uint64_t>(std::llround(max_gap_s * 1e6)) : 0) {}

double PlayClock::due_ms(int64_t timestamp_us) {
  last_cut_us_ = 0;
  if (!started_) {
    started_ = true;
    latest_us_ = timestamp_us;
  }
  if (timestamp_us > latest_us_) {
    // Unsigned, so that log times of any sign and size do not overflow; the
    // pauses add up to at most the span of log time, which fits.
    const uint64_t pause = static_cast<uint64_t>(timestamp_us) - static_cast<uint64_t>(latest_us_);
    const uint64_t played = max_gap_us_ > 0 ? std::min(pause, max_gap_us_) : pause;
    last_cut_us_ = pause - played;
    played_us_ += played;
    latest_us_ = timestamp_us;
  }
  return speed_ > 0 ? static_cast<double>(played_us_) / 1000.0 / speed_ : 0.0;
}

// The stream's clock across files, and the wall time play began.
struct LogPlayer::Pacing {
  explicit Pacing(const LogPlayerOptions& options) : clock(options.speed, options.max_gap_s) {}
  PlayClock clock;
  bool started = false;
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
  Pacing pacing(options_);
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
      pacing.start_ms = monotonic_ms();
    }
    const double due = pacing.clock.due_ms(event.timestamp);
    if (pacing.clock.last_cut_us() > 0) report_cut(reader, event, pacing.clock.last_cut_us());
    if (!wait_until(pacing.start_ms + due)) return false;
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

void LogPlayer::report_cut(const logio::LogReader& reader, const logio::LogEvent& event, uint64_t cut_us) {
  heartbeat_.set_counter("shortened_pauses", ++counts_.shortened_pauses);
  spdlog::warn(
      "{}: event {} (byte {}, {}) comes {:.1f} s of log time after the one before: "
      "the pause is cut to {} s (--max-gap-s)",
      reader.path(), event.event_number, event.offset, event.channel,
      static_cast<double>(cut_us) / 1e6 + options_.max_gap_s, options_.max_gap_s);
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
