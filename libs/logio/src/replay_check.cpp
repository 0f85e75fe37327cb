#include "ivoa/logio/replay_check.hpp"

#include <filesystem>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/log_reader.hpp"

namespace ivoa::logio {

std::string why_lcm_cannot_replay(const std::string& lcm_url) {
  const std::string path = replayed_log(lcm_url.empty() ? default_lcm_url() : lcm_url);
  std::error_code error;
  if (path.empty() || !std::filesystem::is_regular_file(path, error)) return "";
  try {
    LogReader reader(path, {/*resync=*/true, /*headers_only=*/true});
    LogEvent event;
    int64_t after_damage = 0;
    while (reader.next(event)) after_damage += reader.clean() ? 0 : 1;
    if (const std::string not_a_log = reader.not_a_log(); !not_a_log.empty()) return path + ": " + not_a_log;
    if (reader.clean()) return "";
    return path + ": damaged at " + reader.problems().front().describe() + ". LCM's reader stops there, or crashes" +
           (after_damage > 0 ? ", and " + std::to_string(after_damage) + " good events after it would not be read"
                             : std::string()) +
           ". ivoa-log-play plays the log, skipping the damage (ivoa-log-check lists every damaged stretch)";
  } catch (const LogReadError& e) {
    return e.what();
  }
}

void refuse_a_log_lcm_cannot_replay(const std::string& lcm_url) {
  if (const std::string why = why_lcm_cannot_replay(lcm_url); !why.empty()) throw BusError(why, kExitBadInput);
}

}  // namespace ivoa::logio
