// ivoa-live-score: how the introspection a log recorded did against the
// depth monitor's labels of the same frames, and how long it took (see
// README.md). Several files (a split session, in order) are one recording.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <type_traits>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "live_score.hpp"

namespace {

using namespace ivoa;
using tools::LiveScore;

struct ReadCounts {
  int64_t undecodable = 0;  // events on the scored channels that are not their type
  int64_t malformed = 0;    // of their type, with values the scorer cannot use
  int64_t damaged_files = 0;
  int64_t skipped_predictions = 0, skipped_labels = 0;  // of the two above, INTROSPECTION's and the labels'
};

// Decodes the event as Msg for the scorer; one that does not decode, or
// that the scorer leaves out, is counted and skipped.
template <class Msg>
void feed(const std::string& path, const logio::LogEvent& e, tools::LiveScorer& scorer, ReadCounts& counts) {
  Msg m;
  const auto skipped = [&counts] {
    if constexpr (std::is_same_v<Msg, introspection_t>) ++counts.skipped_predictions;
    if constexpr (std::is_same_v<Msg, introspection_labels_t>) ++counts.skipped_labels;
  };
  if (!logio::decode(e, m)) {
    ++counts.undecodable;
    skipped();
    spdlog::warn("{}: byte {}: a {} event that does not decode as its type, skipped", path, e.offset, e.channel);
    return;
  }
  if (const std::string why = scorer.add(m); !why.empty()) {
    ++counts.malformed;
    skipped();
    spdlog::warn("{}: byte {}: {} utime {}: {}, skipped", path, e.offset, e.channel, m.utime, why);
  }
}

// The channels scored (defaults: the processes' own).
struct ScoredChannels {
  std::string predictions{channels::kIntrospection};
  std::string labels{channels::kIntrospectionLabels};
  std::string grid{channels::kObstaclesStereo};
};

// Feeds every prediction, label and detector-grid event to the scorer;
// damage is reported and read past with --resync.
void read_log(const std::string& path, bool resync, const ScoredChannels& ch, tools::LiveScorer& scorer,
              ReadCounts& counts) {
  logio::LogReader reader(path, {resync});
  logio::LogEvent e;
  while (reader.next(e)) {
    if (e.channel == ch.predictions) feed<introspection_t>(path, e, scorer, counts);
    else if (e.channel == ch.labels) feed<introspection_labels_t>(path, e, scorer, counts);
    else if (e.channel == ch.grid) feed<obstacle_grid_t>(path, e, scorer, counts);
  }
  if (const std::string why = reader.not_a_log(); !why.empty()) spdlog::warn("{}: {}", path, why);
  else
    for (const auto& p : reader.problems())
      spdlog::warn("{}: {}{}", path, p.describe(), resync ? "" : " (--resync reads on past it)");
  if (!reader.clean()) ++counts.damaged_files;
}

std::string join(const std::set<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "-" : out;
}

std::string fraction(double x) { return std::isnan(x) ? "  n/a" : fmt::format("{:5.3f}", x); }

void print_row(const char* name, const LabelConfusion& c, int64_t of) {
  std::printf("  %-30s %6lld %5.1f %%  %s  %s  %s  %s  %s  %s\n", name, static_cast<long long>(c.total()),
              of ? 100.0 * static_cast<double>(c.total()) / static_cast<double>(of) : 0.0,
              fraction(c.recall(0)).c_str(), fraction(c.recall(1)).c_str(), fraction(c.recall(2)).c_str(),
              fraction(c.recall(3)).c_str(), fraction(c.mean_per_class()).c_str(), fraction(c.overall()).c_str());
}

void print_score(const LiveScore& s) {
  std::printf("model: %s; labels about: %s\n", join(s.models).c_str(), join(s.detectors).c_str());
  std::printf("frames: %lld labelled, %lld predicted, %lld both (scored); %lld labelled cells in them\n",
              static_cast<long long>(s.labelled_frames), static_cast<long long>(s.predicted_frames),
              static_cast<long long>(s.scored_frames), static_cast<long long>(s.labelled_cells));
  if (s.repeated_messages > 0)
    std::printf("repeated: %lld messages for frames already read (a run recorded twice?), each frame counted once\n",
                static_cast<long long>(s.repeated_messages));
  if (s.outside_view_cells || s.no_grid_cells || s.unmatched_cells)
    std::printf(
        "not scored: %lld outside the introspection's view (patch leaves the image), %lld in frames it "
        "predicted before any detector grid came, %lld others without a prediction\n",
        static_cast<long long>(s.outside_view_cells), static_cast<long long>(s.no_grid_cells),
        static_cast<long long>(s.unmatched_cells));
  std::printf("\n  %-30s %6s %7s  %5s  %5s  %5s  %5s  %5s  %5s\n", "prediction", "cells", "kept", "TP", "TN", "FP",
              "FN", "mean", "all");
  const int64_t matched = s.image.all.total();
  print_row("from the image alone", s.image.all, matched);
  print_row("  announced (under the gate)", s.image.announced, matched);
  print_row("given the detector's verdict", s.given_verdict.all, matched);
  print_row("  announced (under its gate)", s.given_verdict.announced, matched);
  std::printf(
      "  (per class: recall; mean: mean per-class accuracy, the paper's; all: overall accuracy; kept: share "
      "of the %lld matched cells)\n",
      static_cast<long long>(matched));
  if (s.verdict_unknown || s.verdict_disagrees)
    std::printf(
        "verdicts: %lld cells without one (no detector grid reached the introspection), %lld where it is not "
        "the one the label was made from\n",
        static_cast<long long>(s.verdict_unknown), static_cast<long long>(s.verdict_disagrees));
  std::printf(
      "\ncompute per frame (compute_ms): median %.1f ms, 90th percentile %.1f ms, max %.1f ms over %lld frames\n",
      s.compute.median, s.compute.p90, s.compute.max, static_cast<long long>(s.compute.frames));
}

std::string counts_json(const LabelConfusion& c) {
  std::string rows;
  for (int label = 0; label < LabelConfusion::kLabels; ++label)
    rows += fmt::format("{}[{}, {}, {}, {}]", label ? ", " : "", c.counts[label][0], c.counts[label][1],
                        c.counts[label][2], c.counts[label][3]);
  const auto num = [](double x) { return std::isnan(x) ? std::string("null") : fmt::format("{:.6f}", x); };
  return fmt::format("{{\"cells\": {}, \"mean_per_class\": {}, \"overall\": {}, \"confusion\": [{}]}}", c.total(),
                     num(c.mean_per_class()), num(c.overall()), rows);
}

std::string score_json(const LiveScore& s) {
  std::string models, detectors;
  for (const auto& m : s.models) models += (models.empty() ? "" : ", ") + json_quote(m);
  for (const auto& d : s.detectors) detectors += (detectors.empty() ? "" : ", ") + json_quote(d);
  return fmt::format(
      "{{\"models\": [{}], \"detectors\": [{}], \"labelled_frames\": {}, \"predicted_frames\": {}, "
      "\"repeated_messages\": {}, "
      "\"scored_frames\": {}, \"labelled_cells\": {}, \"outside_view_cells\": {}, \"no_grid_cells\": {}, "
      "\"unmatched_cells\": {}, \"verdict_unknown\": {}, "
      "\"verdict_disagrees\": {},\n \"image\": {{\"all\": {}, \"announced\": {}}},\n \"given_verdict\": {{\"all\": {}, "
      "\"announced\": {}}},\n \"compute_ms\": {{\"frames\": {}, \"median\": {:.3f}, \"p90\": {:.3f}, \"max\": "
      "{:.3f}}}, "
      "\"class_order\": [\"TP\", \"TN\", \"FP\", \"FN\"]}}\n",
      models, detectors, s.labelled_frames, s.predicted_frames, s.repeated_messages, s.scored_frames, s.labelled_cells,
      s.outside_view_cells, s.no_grid_cells, s.unmatched_cells, s.verdict_unknown, s.verdict_disagrees,
      counts_json(s.image.all), counts_json(s.image.announced), counts_json(s.given_verdict.all),
      counts_json(s.given_verdict.announced), s.compute.frames, s.compute.median, s.compute.p90, s.compute.max);
}

struct ScoreCommandLine {
  std::vector<std::string> files;
  std::string json_path;
  bool resync = false;
  ScoredChannels channels;

  // The logs, for messages: "FILE" or "FILE (and N more)".
  std::string logs() const {
    return files.size() == 1 ? files[0] : files[0] + " (and " + std::to_string(files.size() - 1) + " more)";
  }
};

void add_score_options(CLI::App& app, ScoreCommandLine& cl) {
  app.add_option("files", cl.files, "log files, in recording order (a split session is read as one)")
      ->required()
      ->check(ivoa::input_file());
  app.add_flag("--resync", cl.resync, "skip damaged parts and read on (default: stop at the first damage)");
  app.add_option("--json", cl.json_path, "also write the counts and figures as JSON to this file");
  add_log_channel_option(app, "--introspection-channel", cl.channels.predictions, "predictions (introspection_t)");
  add_log_channel_option(app, "--labels-channel", cl.channels.labels, "the monitor's labels (introspection_labels_t)");
  add_log_channel_option(app, "--grid-channel", cl.channels.grid,
                         "the detector's grids, whose verdicts the predictions are given (obstacle_grid_t)");
}

// Reads every log into `s`; false (after saying why) when one is unreadable
// or the logs hold nothing to score.
bool score_logs(const ScoreCommandLine& cl, LiveScore& s, ReadCounts& counts) {
  tools::LiveScorer scorer;
  try {
    for (const auto& path : cl.files) read_log(path, cl.resync, cl.channels, scorer, counts);
  } catch (const logio::LogReadError& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  s = scorer.finish();
  if (s.predicted_frames > 0 && s.labelled_frames > 0) return true;
  // Messages left out as unusable are not missing ones: say which it was.
  const int64_t left_out = s.predicted_frames == 0 ? counts.skipped_predictions : counts.skipped_labels;
  const std::string skipped =
      left_out ? fmt::format(" that could be used ({} left out as unusable or undecodable: warnings above)", left_out)
               : "";
  const bool cut_short = counts.damaged_files > 0 && !cl.resync;
  spdlog::error("{}: no {} messages{} to score{}", cl.logs(),
                s.predicted_frames == 0 ? cl.channels.predictions : cl.channels.labels, skipped,
                !skipped.empty()          ? ""
                : cut_short               ? " in what was read before the damage (--resync reads on past it)"
                : s.predicted_frames == 0 ? " (was ivoa-introspection running when it was recorded?)"
                                          : " (was ivoa-depth-monitor running, with a depth sensor? ivoa-log-check "
                                            "shows its last heartbeat: stereo_unmatched near its in count means no "
                                            "depth frame was near the stereo frames, see its --sync-tolerance-us)");
  return false;
}

// Prints the score and writes the JSON; the exit code.
int report(const ScoreCommandLine& cl, const LiveScore& s, const ReadCounts& counts) {
  print_score(s);
  if (counts.undecodable || counts.malformed || counts.damaged_files)
    std::printf(
        "skipped: %lld undecodable messages; %lld with values that cannot be scored; %lld damaged file(s) "
        "(warnings above)\n",
        static_cast<long long>(counts.undecodable), static_cast<long long>(counts.malformed),
        static_cast<long long>(counts.damaged_files));
  if (!write_text_file(cl.json_path, score_json(s))) return kExitIoError;
  if (s.scored_frames == 0) {
    spdlog::error("{}: no frame has both {} and {} (their utimes never match)", cl.logs(), cl.channels.predictions,
                  cl.channels.labels);
    return kExitBadInput;
  }
  if (s.image.all.total() == 0) {  // frames matched, but no cell: every figure above is n/a
    spdlog::error("{}: no labelled cell has a prediction in the {} frames with both ({} labelled cells; see above)",
                  cl.logs(), s.scored_frames, s.labelled_cells);
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Score the introspection a log recorded against the depth monitor's labels of the same frames, and "
      "how long it took per frame. Exit codes: 0 scored, 2 bad flags (a --json that is one of the logs, a log given "
      "twice), 3 a log is "
      "unreadable or has nothing to score, 4 the "
      "JSON cannot be written."};
  CommonOptions common;
  add_offline_options(app, common);
  ScoreCommandLine cl;
  add_score_options(app, cl);
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  init_logging("live-score", common.log_level);
  LiveScore s;
  ReadCounts counts;
  if (const std::string twice = file_given_twice(cl.files); !twice.empty()) {
    spdlog::error("{} is given twice: its frames would count twice", twice);
    return kExitUsage;
  }
  if (const std::string log = same_file_among(cl.json_path, cl.files); !log.empty()) {
    spdlog::error("--json {} is the log {}: it would be written over", cl.json_path, log);
    return kExitUsage;
  }
  if (const std::string why = why_cannot_write(cl.json_path); !why.empty()) {
    spdlog::error("--json {}: cannot write: {}", cl.json_path, why);
    return kExitIoError;
  }
  if (!score_logs(cl, s, counts)) return kExitBadInput;
  return report(cl, s, counts);
}
