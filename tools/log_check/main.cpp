// ivoa-log-check: what an LCM log holds and whether it is intact. Per
// channel: type, count, size, sequence-number gaps, utime regressions.
// For a damaged or truncated log: the byte offset of the first bad event
// and how many good events come before it; messages of an ivoa type that
// do not decode as it, per channel. Per process: its last
// heartbeat (final state and counts). Several files (a split session, in
// order) are checked as one recording.
#include <filesystem>
#include <map>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/channel_counts.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/message_registry.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/log_summary.hpp"
#include "ivoa/logio/session_name.hpp"
#include "ivoa/log_check/last_heartbeats.hpp"

namespace {

using ivoa::log_check::LastHeartbeats;
using ivoa::logio::LogSummary;

// Messages on a channel of an ivoa type that a reader of that type skips
// as bad input: framed intact in the log, but not decoding as the type, or
// of no ivoa type at all (damaged at or before the fingerprint, or another
// program's type on the channel).
struct DamagedPayloads {
  std::string type;                   // the channel's ivoa type ("" if none was seen)
  int64_t count = 0;                  // of its fingerprint, not decoding as it
  int64_t untyped = 0;                // of no ivoa type's fingerprint
  uint64_t first_offset = 0;          // of the first not decoding, in the file
  uint64_t first_untyped_offset = 0;  // of the first of no ivoa type
  bool damaged() const { return count > 0 || (untyped > 0 && !type.empty()); }
};

struct FileResult {
  std::string path;
  uint64_t size = 0;
  int64_t events = 0;
  std::string first_channel;
  std::vector<ivoa::logio::LogProblem> problems;
  std::vector<int64_t> events_before_problem;          // per problem
  std::map<std::string, DamagedPayloads> undecodable;  // per channel, only those damaged() after the file
  std::string error;                                   // could not be read at all
  bool damaged() const { return !error.empty() || !problems.empty() || !undecodable.empty(); }
};

void check_payload(const ivoa::logio::LogEvent& event, FileResult& r) {
  const auto type = ivoa::payload_type_name(event.data.data(), event.data.size());
  DamagedPayloads& d = r.undecodable[event.channel];
  if (type) {
    if (d.type.empty()) d.type = std::string(*type);
    if (!ivoa::ivoa_payload_damaged(event.data.data(), event.data.size())) return;
    if (d.count++ == 0) d.first_offset = event.offset;
  } else if (d.untyped++ == 0) {
    d.first_untyped_offset = event.offset;
  }
}

// Keeps the channels with damaged payloads: untyped messages count only on
// a channel that also carries an ivoa type.
void keep_damaged_channels(FileResult& r) {
  for (auto it = r.undecodable.begin(); it != r.undecodable.end();)
    it = it->second.damaged() ? std::next(it) : r.undecodable.erase(it);
}

FileResult check_file(const std::string& path, bool resync, LogSummary& summary, LastHeartbeats& heartbeats) {
  FileResult r;
  r.path = path;
  try {
    ivoa::logio::LogReader reader(path, {resync});
    r.size = reader.size();
    ivoa::logio::LogEvent event;
    size_t problems_seen = 0;
    while (true) {
      const bool got = reader.next(event);
      for (; problems_seen < reader.problems().size(); ++problems_seen) r.events_before_problem.push_back(r.events);
      if (!got) break;
      if (r.events++ == 0) r.first_channel = event.channel;
      check_payload(event, r);
      summary.add(event);
      heartbeats.add(event);
    }
    r.problems = reader.problems();
    keep_damaged_channels(r);
    if (std::string why = reader.not_a_log(); !why.empty()) {
      if (std::filesystem::path(path).extension() == ".json")
        why +=
            "; a .json beside a log is ivoa-logger's sidecar (a summary of the log): give the logs only, e.g. "
            "run.lcmlog.[0-9][0-9]";
      r.error = why;
      r.problems.clear();
      r.events_before_problem.clear();
      r.undecodable.clear();
    }
  } catch (const ivoa::logio::LogReadError& e) {
    r.error = e.what();
  }
  return r;
}

void print_file(const FileResult& r) {
  if (!r.error.empty()) {
    std::printf("%s: UNREADABLE: %s\n", r.path.c_str(), r.error.c_str());
    return;
  }
  std::printf("%s: %lld events, %.1f MB, first channel %s, %s\n", r.path.c_str(), static_cast<long long>(r.events),
              static_cast<double>(r.size) / 1e6, r.first_channel.empty() ? "-" : r.first_channel.c_str(),
              r.damaged()     ? "DAMAGED"
              : r.events == 0 ? "intact but empty (nothing recorded; ivoa-log-play refuses it)"
                              : "intact");
  for (size_t i = 0; i < r.problems.size(); ++i)
    std::printf(
        "  %s; the %lld events before it are intact%s\n", r.problems[i].describe().c_str(),
        static_cast<long long>(r.events_before_problem[i]),
        r.problems[i].cut_short && r.problems[i].to_end ? " (the recording stopped while writing this event)" : "");
  for (const auto& [channel, d] : r.undecodable) {
    if (d.count > 0)
      std::printf(
          "  %s: %lld messages do not decode as %s (truncated or damaged inside; readers skip them), the first at "
          "byte %llu\n",
          channel.c_str(), static_cast<long long>(d.count), d.type.c_str(),
          static_cast<unsigned long long>(d.first_offset));
    if (d.untyped > 0)
      std::printf(
          "  %s: %lld messages are of no ivoa type among its %s messages (damaged at or before the fingerprint, "
          "or another program's type; readers skip them), the first at byte %llu\n",
          channel.c_str(), static_cast<long long>(d.untyped), d.type.c_str(),
          static_cast<unsigned long long>(d.first_untyped_offset));
  }
}

std::string results_json(const std::vector<FileResult>& files, const LogSummary& summary,
                         const LastHeartbeats& heartbeats) {
  using ivoa::json_quote;
  std::string out = "{\"files\": [";
  for (size_t i = 0; i < files.size(); ++i) {
    const FileResult& f = files[i];
    out += std::string(i ? ",\n  " : "\n  ") + "{\"path\": " + json_quote(f.path) +
           ", \"bytes\": " + std::to_string(f.size) + ", \"events\": " + std::to_string(f.events) +
           ", \"first_channel\": " + json_quote(f.first_channel) + ", \"error\": " + json_quote(f.error) +
           ", \"problems\": [";
    for (size_t k = 0; k < f.problems.size(); ++k)
      out += std::string(k ? ", " : "") + "{\"offset\": " + std::to_string(f.problems[k].offset) +
             ", \"what\": " + json_quote(f.problems[k].what) +
             ", \"skipped_bytes\": " + std::to_string(f.problems[k].skipped_bytes) +
             ", \"cut_short\": " + (f.problems[k].cut_short ? "true" : "false") +
             ", \"events_before\": " + std::to_string(f.events_before_problem[k]) + "}";
    out += "], \"undecodable\": {";
    const char* sep = "";
    for (const auto& [channel, d] : f.undecodable) {
      out += sep + json_quote(channel) + ": {\"type\": " + json_quote(d.type) +
             ", \"count\": " + std::to_string(d.count) + ", \"first_offset\": " + std::to_string(d.first_offset) +
             ", \"untyped\": " + std::to_string(d.untyped) +
             ", \"first_untyped_offset\": " + std::to_string(d.first_untyped_offset) + "}";
      sep = ", ";
    }
    out += "}}";
  }
  out += "],\n\"events\": " + std::to_string(summary.events()) + ",\n\"channels\": {";
  const char* sep = "\n  ";
  for (const auto& [name, channel] : summary.channels()) {
    out += sep + json_quote(name) + ": " + ivoa::logio::channel_json(channel);
    sep = ",\n  ";
  }
  return out + "},\n\"processes\": " + heartbeats.json() + "}\n";
}

// False (with a message) if a channel's count of messages of its own type
// is not the one expected: a frame replaced by another type is a frame lost.
bool expectations_hold(const std::map<std::string, int64_t>& expect, const LogSummary& summary) {
  bool ok = true;
  for (const auto& [channel, want] : expect) {
    const auto it = summary.channels().find(channel);
    const int64_t got = it == summary.channels().end() ? 0 : it->second.typed;
    if (got != want) {
      const int64_t others = it == summary.channels().end() ? 0 : it->second.other_fingerprints;
      spdlog::error("{}: expected {} messages, the log has {}{}", channel, want, got,
                    others ? fmt::format(" of {} (and {} of other types)", it->second.type, others) : "");
      ok = false;
    }
  }
  return ok;
}

bool sequences_complete(const LogSummary& summary) {
  bool ok = true;
  for (const auto& [name, s] : summary.channels()) {
    if (s.missing_seq == 0 && s.seq_regressions == 0) continue;
    spdlog::error("{}: {} messages missing by sequence number, {} repeated or out of order", name, s.missing_seq,
                  s.seq_regressions);
    ok = false;
  }
  return ok;
}

struct CheckCommandLine {
  std::vector<std::string> files, expect;
  std::map<std::string, int64_t> expected;  // expect, parsed
  std::string json_path;
  bool resync = false, no_gaps = false;
};

void add_check_options(CLI::App& app, CheckCommandLine& cl) {
  app.add_option("files", cl.files, "log files, in recording order (a split session is checked as one)")->required();
  app.add_flag("--resync", cl.resync, "skip damaged parts and read on (default: stop at the first damage)");
  app.add_option("--json", cl.json_path, "also write the results as JSON to this file");
  app.add_option("--expect", cl.expect, "CHANNEL=N: fail unless the log has exactly N messages of CHANNEL's type on it")
      ->delimiter(',')
      ->check([](const std::string& s) {
        try {
          ivoa::parse_channel_counts({s}, "");  // CLI11 names the option
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      });
  app.add_flag("--no-gaps", cl.no_gaps,
               "fail if a sequence-numbered channel misses or repeats a message (a publisher that started again, its "
               "seq going back as time went on, is neither)");
}

// Reads and prints every file, then the summary, the JSON and the verdict
// (the exit code).
int check_logs(const CheckCommandLine& cl) {
  LogSummary summary;
  LastHeartbeats heartbeats;
  std::vector<FileResult> results;
  bool damaged = false;
  for (const auto& path : cl.files) {
    results.push_back(check_file(path, cl.resync, summary, heartbeats));
    print_file(results.back());
    damaged = damaged || results.back().damaged();
  }
  if (summary.events() > 0) std::printf("\n%s", summary.table().c_str());
  else std::printf("\nno message read\n");
  if (const std::string table = heartbeats.table(); !table.empty()) std::printf("\n%s", table.c_str());
  if (!ivoa::write_text_file(cl.json_path, results_json(results, summary, heartbeats))) return ivoa::kExitIoError;
  const bool expected = expectations_hold(cl.expected, summary);
  const bool complete = !cl.no_gaps || sequences_complete(summary);
  if (damaged) return ivoa::kExitBadInput;
  return expected && complete ? ivoa::kExitOk : ivoa::kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Check LCM log files: per-channel counts, types, sequence gaps, utime< (messages older than the one before); the "
      "byte offset of any damage, messages "
      "that do not decode as their type; each process's last heartbeat.\n"
      "Exit codes: 0 intact (and expectations met), 1 an expectation failed, 2 bad flags (a --json that is one of "
      "the logs), 3 a log is damaged or "
      "unreadable, 4 the --json file cannot be written."};
  ivoa::CommonOptions common;
  ivoa::add_offline_options(app, common);
  CheckCommandLine cl;
  add_check_options(app, cl);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("log-check", common.log_level);
  try {  // each CHANNEL=N was checked while parsing; a channel given twice only here
    cl.expected = ivoa::parse_channel_counts(cl.expect, "--expect");
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  if (const std::string twice = ivoa::file_given_twice(cl.files); !twice.empty()) {
    spdlog::error("{} is given twice: its messages would count twice (as repeats and a restart)", twice);
    return ivoa::kExitUsage;
  }
  if (const std::string log = ivoa::same_file_among(cl.json_path, cl.files); !log.empty()) {
    spdlog::error("--json {} is the log {}: it would be written over", cl.json_path, log);
    return ivoa::kExitUsage;
  }
  if (const std::string order = ivoa::logio::split_parts_out_of_order(cl.files); !order.empty())
    spdlog::warn(
        "split parts given out of order? {} (read so, time goes back between them: a restart below may be "
        "that)",
        order);
  if (const std::string why = ivoa::why_cannot_write(cl.json_path); !why.empty()) {
    spdlog::error("--json {}: cannot write: {}", cl.json_path, why);
    return ivoa::kExitIoError;
  }
  return check_logs(cl);
}
