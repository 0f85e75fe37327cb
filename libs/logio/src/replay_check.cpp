#include "ivoa/logio/replay_check.hpp"

#include <filesystem>

#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/log_reader.hpp"

namespace ivoa::logio {
namespace {

// The log file `lcm_url` replays (the default URL if empty), or "".
std::string log_replayed_by(const std::string& lcm_url) {
  return replayed_log(lcm_url.empty() ? default_lcm_url() : lcm_url);
}

// LCM reads up to a last event the file ends inside, then stops as at the
// end: nothing is lost that any reader could play.
bool only_the_last_event_is_cut_short(const std::vector<LogProblem>& problems) {
  return problems.size() == 1 && problems.front().to_end && problems.front().cut_short;
}

}  // namespace

ReplayCheck check_log_for_replay(const std::string& lcm_url) {
  const std::string path = log_replayed_by(lcm_url);
  std::error_code error;
  if (path.empty() || !std::filesystem::is_regular_file(path, error)) return {};
  try {
    LogReader reader(path, {/*resync=*/true, /*headers_only=*/true});
    LogEvent event;
    int64_t before_damage = 0;
    int64_t after_damage = 0;
    while (reader.next(event)) (reader.clean() ? before_damage : after_damage) += 1;
    if (const std::string not_a_log = reader.not_a_log(); !not_a_log.empty()) return {path + ": " + not_a_log, ""};
    if (reader.clean()) return {};
    const LogProblem& first = reader.problems().front();
    if (only_the_last_event_is_cut_short(reader.problems()))
      return {"", path + ": its last event, at byte " + std::to_string(first.offset) + ", is cut short (" + first.what +
                      "): the recording stopped while writing it. The " + std::to_string(before_damage) +
                      " events before it are played"};
    return {path + ": damaged at " + first.describe() + ". LCM's reader stops there, or crashes" +
                (after_damage > 0 ? ", and " + std::to_string(after_damage) + " good events after it would not be read"
                                  : std::string()) +
                ". ivoa-log-play plays the log, skipping the damage (ivoa-log-check lists every damaged stretch)",
            ""};
  } catch (const LogReadError& e) {
    return {e.what(), ""};
  }
}

void refuse_a_log_lcm_cannot_replay(const std::string& lcm_url) {
  const ReplayCheck check = check_log_for_replay(lcm_url);
  if (!check.refusal.empty()) throw BusError(check.refusal, kExitBadInput);
  if (!check.warning.empty()) spdlog::warn("{}", check.warning);
}

bool warn_that_a_replay_publishes_nothing(const std::string& lcm_url, const std::string& outputs) {
  const std::string path = log_replayed_by(lcm_url);
  if (path.empty()) return false;
  spdlog::warn(
      "reading the log {}: LCM cannot publish into a log it reads, so {} are computed and counted as "
      "publish_failures, not sent. To see them, play the log to this process with ivoa-log-play",
      path, outputs);
  return true;
}

}  // namespace ivoa::logio
