// ivoa-log-play: plays recorded LCM logs into LCM as they were recorded;
// the split files of one session (run.lcmlog.00 .01 ...) as one stream.
//   ivoa-log-play logs/record-20261202-212245.lcmlog.[0-9][0-9]
//   ivoa-log-play --speed 0.5 -c '^(STEREO_IMAGES|DEPTH_IMAGE|RIG_CALIBRATION)$' session.lcmlog

#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/log_play/log_player.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/session_name.hpp"

namespace {

// The log a file://PATH?mode=w (or mode=a) URL would write, if it already
// exists as one of the logs to play: mode=w would empty it before a byte of
// it is read, mode=a would append it to itself.
std::string output_among_inputs(const std::string& url, const std::vector<std::string>& logs) {
  const bool writes = url.find("mode=w") != std::string::npos || url.find("mode=a") != std::string::npos;
  if (url.rfind("file://", 0) != 0 || !writes) return {};
  return ivoa::same_file_among(url.substr(7, url.find('?') - 7), logs);
}

// Why a file://PATH?mode=w output does not hold the `published` events
// ("" if it does, or the output is not such a file). LCM writes it through
// stdio and says nothing of a full disk: the play reported success over a
// cut log.
std::string why_output_short(const std::string& url, int64_t published) {
  if (url.rfind("file://", 0) != 0 || url.find("mode=w") == std::string::npos) return "";
  const std::string path = url.substr(7, url.find('?') - 7);
  try {
    ivoa::logio::LogReader reader(path);
    ivoa::logio::LogEvent e;
    int64_t events = 0;
    while (reader.next(e)) ++events;
    // Our own heartbeats are in it too, so at least as many.
    if (events >= published && reader.clean()) return "";
    return fmt::format("{} holds {} whole events for {} published{} (a full disk?)", path, events, published,
                       reader.clean() ? "" : ", then " + reader.problems().front().describe());
  } catch (const ivoa::logio::LogReadError& e) {
    return e.what();
  }
}

struct PlayResult {
  int exit_code = ivoa::kExitOk;
  int64_t published = 0;
};

PlayResult play(const ivoa::CommonOptions& common, const std::vector<std::string>& logs,
                const ivoa::log_play::LogPlayerOptions& options) {
  ivoa::Bus bus(common.lcm_url);
  ivoa::Heartbeat heartbeat(bus, "log_play", common.status_channel);
  ivoa::log_play::LogPlayer player(bus, heartbeat, logs, options);
  const bool whole = player.play();
  const auto& c = player.counts();
  heartbeat.set_state(whole ? "finished" : "stopped");
  heartbeat.publish_now();
  spdlog::info(
      "{}: {} of {} files{}, {} events published{}, {} of other channels, {} damaged stretches skipped, "
      "{} long pauses cut short",
      whole ? "finished" : "stopped", c.files_done, logs.size(),
      c.not_logs > 0 ? fmt::format(" ({} of them no LCM log: nothing played from it)", c.not_logs) : "", c.published,
      c.publish_failures > 0 ? fmt::format(" ({} refused by LCM: not published)", c.publish_failures) : "",
      c.filtered_out, c.damaged, c.shortened_pauses);
  if (c.published == 0 && c.filtered_out > 0)
    spdlog::warn("no event matched -c '{}'{}: the logs' channels were all left out", options.channels,
                 options.exclude.empty() ? "" : " and -x '" + options.exclude + "'");
  PlayResult r;
  r.published = c.published;
  r.exit_code = c.publish_failures > 0 ? ivoa::kExitFailure : c.not_logs > 0 ? ivoa::kExitBadInput : ivoa::kExitOk;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Play LCM logs into LCM at the recorded pace; several files (the split files of one session, in order) "
      "play as one stream. Damaged stretches are skipped and reported. Exit codes: 0 played (or stopped), "
      "1 LCM failure or a message LCM refused, 2 bad flags (an output log that is one of the logs to play among "
      "them), 3 a log cannot be opened (nothing played) or holds no event (the others played), 4 a file:// output "
      "that cannot be written."};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  std::vector<std::string> logs;
  ivoa::log_play::LogPlayerOptions options;
  app.add_option("logs", logs, "LCM log files, played in the order given")->required();
  app.add_option("-s,--speed", options.speed, "multiple of the recorded pace (0: as fast as possible)")
      ->check(ivoa::non_negative_number())
      ->capture_default_str();
  app.add_option("--max-gap-s", options.max_gap_s,
                 "a pause in the log longer than this (s of log time) is cut to it and reported, so a clock jump "
                 "is not waited out (0: every pause as recorded)")
      ->check(ivoa::number_in(0, 1e6))
      ->capture_default_str();
  app.add_option("-c,--channels", options.channels, "play the channels matching this regex (whole name)")
      ->capture_default_str();
  app.add_option("-x,--exclude", options.exclude, "leave out the channels matching this regex");
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("log_play", common.log_level);
  ivoa::install_stop_handlers();
  if (const std::string same = output_among_inputs(common.lcm_url, logs); !same.empty()) {
    spdlog::error("--lcm-url {} would write over {}, one of the logs to play: name another output file", common.lcm_url,
                  same);
    return ivoa::kExitUsage;
  }
  if (const std::string order = ivoa::logio::split_parts_out_of_order(logs); !order.empty()) {
    spdlog::error("split parts given out of order: give {} (played out of order, time would go back)", order);
    return ivoa::kExitUsage;
  }
  if (const std::string twice = ivoa::file_given_twice(logs); !twice.empty()) {
    spdlog::error("{} is given twice: it would play twice, time going back between", twice);
    return ivoa::kExitUsage;
  }
  try {
    const PlayResult r = play(common, logs, options);  // the output file is closed on return
    if (r.exit_code != ivoa::kExitOk) return r.exit_code;
    if (const std::string why = why_output_short(common.lcm_url, r.published); !why.empty()) {
      spdlog::error("the output log is not whole: {}", why);
      return ivoa::kExitIoError;
    }
    return ivoa::kExitOk;
  } catch (const ivoa::logio::LogReadError& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
