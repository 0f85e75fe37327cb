// ivoa-dataset: LCM logs -> training dataset (one session per log, or per
// group of split files), and a summary of existing datasets.
//
//   ivoa-dataset build --out data/ --labels jppc session1.lcmlog session2.lcmlog
//   ivoa-dataset build --out data/ --labels recorded --session s7 s7.lcmlog.00 s7.lcmlog.01
//   ivoa-dataset info data/ [--split split.yaml]
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/labels.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/progress.hpp"
#include "ivoa/dataset/builder.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/session_name.hpp"
#include "ivoa/stereo/config.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/options.hpp"

namespace fs = std::filesystem;
using namespace ivoa;

namespace {

// Recorded labels come with the grid and detector the live processes used:
// only the patch cut around their cells can change. Applies --patch-size and
// returns the first other relabelling flag given (it would be ignored), if any.
const CLI::Option* ignored_with_recorded_labels(const std::vector<CLI::Option*>& relabel_flags,
                                                const CLI::Option& patch_size, dataset::BuildOptions& options) {
  if (patch_size.count() > 0) options.recorded_patch_size = options.grid.patch_size;
  for (const CLI::Option* flag : relabel_flags)
    if (flag != &patch_size && flag->count() > 0) return flag;
  return nullptr;
}

std::string class_counts(const std::array<int64_t, dataset::kNumClasses>& c) {
  std::string out;
  for (int k = 0; k < dataset::kNumClasses; ++k)
    out += std::string(k ? "  " : "") + kLabelNames[static_cast<size_t>(k)] + " " +
           std::to_string(c[static_cast<size_t>(k)]);
  return out;
}

int build_session(const std::string& out, const std::string& session, const std::vector<std::string>& logs,
                  const dataset::BuildOptions& options) {
  uint64_t total = 0;
  std::error_code no_size;  // a log that cannot be read is named by the builder
  for (const auto& log : logs) total += fs::is_regular_file(log) ? fs::file_size(log, no_size) : 0;
  Progress progress("session " + session, static_cast<double>(total) / 1e6, "MB");
  dataset::SessionBuilder builder(out, session, options);
  uint64_t before = 0;
  for (const auto& log : logs) {
    builder.add_log(log, [&](uint64_t done, uint64_t) { progress.update(static_cast<double>(before + done) / 1e6); });
    before += fs::file_size(log, no_size);
  }
  const dataset::BuildReport r = builder.finish();
  progress.finish(std::to_string(r.stereo_frames) + " frames");
  std::printf("%-28s frames %5lld labelled %5lld unmatched %4lld  samples %7lld  %s\n", session.c_str(),
              static_cast<long long>(r.stereo_frames), static_cast<long long>(r.frames_labelled),
              static_cast<long long>(r.frames_unmatched), static_cast<long long>(r.samples),
              class_counts(r.class_counts).c_str());
  if (r.tn_dropped > 0)
    std::printf("%-28s %lld TN cells left out (--keep-tn %g)\n", "", static_cast<long long>(r.tn_dropped),
                options.keep_tn);
  if (r.patches_outside > 0)
    std::printf("%-28s %lld labelled cells skipped: their patch leaves the image\n", "",
                static_cast<long long>(r.patches_outside));
  if (r.frames_repeated > 0)
    std::printf("%-28s %lld frames already stored skipped (a log given twice, or frames recorded twice)\n", "",
                static_cast<long long>(r.frames_repeated));
  if (const std::string why = dataset::pairing_warning(r, options.pairing); !why.empty())
    spdlog::warn("{}: {}", session, why);
  if (r.frames_other_size > 0)
    spdlog::warn(
        "{}: {} stereo frames are of another size than the frames its samples start with ({}x{}), the size the session "
        "records and a "
        "model trained on it will know: build each camera's logs as a session of its own",
        session, r.frames_other_size, r.image_size.width, r.image_size.height);
  if (r.samples == 0 && r.patches_outside > 0)
    spdlog::warn("{}: no samples: every labelled cell's patch leaves the image (a smaller --patch-size?)", session);
  if (r.evidence_mismatches > 0)
    std::printf("%-28s %lld samples' evidence left NaN: the re-run detector's verdict differs from the label's\n", "",
                static_cast<long long>(r.evidence_mismatches));
  // Damage and bad messages are skipped, not fatal: the session holds what
  // could be read, as every offline tool does with a damaged log.
  for (const auto& p : r.problems) spdlog::warn("{}: {}", session, p);
  if (!r.problems.empty())
    std::printf("%-28s %zu problem(s) skipped (warnings above: damage with its byte offset, bad messages)\n", "",
                r.problems.size());
  return kExitOk;
}

using SessionLogs = std::vector<std::pair<std::string, std::vector<std::string>>>;

// The folder a log is in, however it is spelt (./a, a/, a symlink to it).
fs::path folder_of(const std::string& log) {
  std::error_code error;
  const fs::path folder = fs::weakly_canonical(fs::absolute(log).parent_path(), error);
  return error ? fs::absolute(log).parent_path() : folder;
}

// A log among one session's `files` that is not the next split part from
// the first one's folder (NAME.lcmlog.00, .01, ... in order), or "" when
// they are one recording.
std::string another_recording_among(const std::vector<std::string>& files) {
  if (files.size() < 2) return "";
  const fs::path folder = folder_of(files.front());
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string& f = files[i];
    const bool in_order = i == 0 || fs::path(f).extension().string() > fs::path(files[i - 1]).extension().string();
    if (!logio::is_split_part(f) || folder_of(f) != folder || !in_order) return i == 0 ? files[1] : f;
  }
  return "";
}

// Whether the logs grouped by name are each one recording: a file given
// twice, or two logs of one name that are not split parts from one folder
// (a scene's session recorded twice, in two folders), were merged into one
// session whose labels were paired with the other log's frames. --session
// joins logs on purpose; a file twice, or split parts out of order, are
// refused even then.
bool sessions_are_recordings(const SessionLogs& sessions, const std::vector<std::string>& logs, bool named_by_flag) {
  if (const std::string twice = file_given_twice(logs); !twice.empty()) {
    spdlog::error("{} is given twice: give each log once", twice);
    return false;
  }
  if (const std::string order = logio::split_parts_out_of_order(logs); !order.empty()) {
    spdlog::error("the split parts of session {} are given out of order: give {}",
                  logio::session_name_of(order.substr(0, order.find(" before "))), order);
    return false;
  }
  if (named_by_flag) return true;
  std::map<std::string, std::string> first_log_of;
  for (const auto& [name, files] : sessions) {
    // The name again after another session's logs, or logs of two recordings in one group.
    const auto [first, new_name] = first_log_of.emplace(name, files.front());
    const std::string other = new_name ? another_recording_among(files) : files.front();
    if (other.empty()) continue;
    spdlog::error(
        "{} and {} are both session {}: give each session's log once (split parts NAME.lcmlog.NN of one folder, in "
        "order, go together; --session NAME joins other logs on purpose)",
        new_name ? files.front() : first->second, other, name);
    return false;
  }
  return true;
}

// The split parts a session's run of them skips (.01 given .00 and .02;
// .00 given only from .01 on), or "" when none: a glob that missed a file
// built a session with a hole in it, silently.
std::string parts_not_given(const std::vector<std::string>& files) {
  int next = 0, missing = 0;
  std::string first, recording;  // --session may join several
  for (const auto& f : files) {
    if (!logio::is_split_part(f)) return "";
    if (const std::string r = fs::path(f).replace_extension().string(); r != recording) recording = r, next = 0;
    const int part = std::stoi(fs::path(f).extension().string().substr(1));
    if (part > next && first.empty()) first = fs::path(f).replace_extension(fmt::format(".{:02d}", next)).string();
    missing += std::max(0, part - next);
    next = part + 1;
  }
  return missing == 0
             ? ""
             : fmt::format("{} split part{} not given (the first: {})", missing, missing == 1 ? "" : "s", first);
}

int run_build(const std::string& out, const std::string& session, const std::vector<std::string>& logs,
              const dataset::BuildOptions& options) {
  // The dataset folder is made and probed first: one that cannot be written
  // is a write error (exit 4), said before any log is read.
  std::error_code made;
  fs::create_directories(out, made);
  const std::string why = made ? made.message() : why_cannot_write((fs::path(out) / ".write-probe").string());
  if (!why.empty()) {
    spdlog::error("cannot write the dataset folder {}: {}", out, why);
    return kExitIoError;
  }
  // Logs of one session (explicit --session, or split files name.NN) go together.
  SessionLogs sessions;
  for (const auto& log : logs) {
    const std::string name = session.empty() ? logio::session_name_of(log) : session;
    if (sessions.empty() || sessions.back().first != name) sessions.push_back({name, {}});
    sessions.back().second.push_back(log);
  }
  if (!sessions_are_recordings(sessions, logs, !session.empty())) return kExitUsage;
  for (const auto& [name, files] : sessions)
    if (const std::string gap = parts_not_given(files); !gap.empty())
      spdlog::warn("session {}: {}: its frames are not in the session", name, gap);
  int worst = kExitOk;
  for (const auto& [name, files] : sessions) {
    try {
      worst = std::max(worst, build_session(out, name, files, options));
    } catch (const logio::LogReadError& e) {
      spdlog::error("{}", e.what());
      worst = kExitBadInput;
    } catch (const dataset::DatasetError& e) {
      spdlog::error("{}", e.what());
      worst = kExitBadInput;
    } catch (const std::exception& e) {  // unforeseen: this session is not registered, the next ones still built
      spdlog::error("session {} ({}): {}; the dataset is left as it was", name, fmt::join(files, ", "), e.what());
      worst = kExitBadInput;
    }
  }
  return worst;
}

int run_info(const std::string& root, const std::string& split_path) {
  std::map<std::string, std::string> split_of;
  if (!split_path.empty())
    for (const auto& [split, sessions] : dataset::load_split(split_path))
      for (const auto& s : sessions) split_of[s] = split;
  const std::vector<std::string> sessions = dataset::list_sessions(root);
  if (sessions.empty()) {
    spdlog::error(
        "{}: not a dataset, or one without sessions (no dataset.json listing any: ivoa-dataset build "
        "--out writes it)",
        root);
    return kExitBadInput;
  }
  std::array<int64_t, dataset::kNumClasses> total{};
  std::map<std::string, int> image_sizes;  // "960x600" -> sessions; "not recorded" for older ones
  int broken = 0;                          // listed and counted; the others are still shown
  for (const auto& name : sessions) {
    std::optional<dataset::SessionReader> r;
    try {
      r.emplace(root + "/" + name);
    } catch (const dataset::DatasetError& e) {
      std::printf("%-28s UNREADABLE: %s\n", name.c_str(), e.what());
      ++broken;
      continue;
    }
    const auto& i = r->info();
    std::printf("%-28s %-6s %-8s %-8s frames %5lld samples %7lld  %s\n", name.c_str(),
                split_of.count(name) ? split_of[name].c_str() : "-", i.environment.c_str(), i.detector.c_str(),
                static_cast<long long>(i.frames), static_cast<long long>(i.samples),
                class_counts(i.class_counts).c_str());
    if (i.evidence_size > 0) std::printf("%-28s evidence: %d values per sample\n", "", i.evidence_size);
    if (i.tn_kept < 1)
      std::printf("%-28s TN thinned to %g: %lld TN cells left out\n", "", i.tn_kept,
                  static_cast<long long>(i.tn_dropped));
    for (int k = 0; k < dataset::kNumClasses; ++k)
      total[static_cast<size_t>(k)] += i.class_counts[static_cast<size_t>(k)];
    ++image_sizes[i.image_size.empty() ? "not recorded"
                                       : fmt::format("{}x{}", i.image_size.width, i.image_size.height)];
  }
  std::printf(
      "total: %s%s\n", class_counts(total).c_str(),
      broken > 0 ? fmt::format(" ({} of {} sessions unreadable, not counted)", broken, sessions.size()).c_str() : "");
  std::vector<std::string> sizes;  // a model trained on these sessions knows these sizes
  for (const auto& [size, count] : image_sizes)
    sizes.push_back(fmt::format("{} ({} session{})", size, count, count == 1 ? "" : "s"));
  std::printf("image sizes: %s\n",
              sizes.empty() ? "none (no readable session)" : fmt::format("{}", fmt::join(sizes, ", ")).c_str());
  for (const auto& [session, split] : split_of)
    if (!fs::exists(root + "/" + session + "/session.json"))
      spdlog::warn("split '{}' names session '{}', which is not in {}", split, session, root);
  return broken > 0 ? kExitBadInput : kExitOk;
}

// What "build" takes: --keep-tn as a fraction in (0, 1].
std::string check_fraction(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  const bool number = !text.empty() && *end == '\0';
  return number && v > 0 && v <= 1 ? std::string() : "must be a number in (0, 1], not '" + text + "'";
}

// What --labels takes: the recorded labels, or a detector to re-run.
std::vector<std::string> label_sources() {
  std::vector<std::string> sources{dataset::kRecordedLabels};
  for (const auto& name : stereo::detector_names()) sources.push_back(name);
  return sources;
}

// A --config file's keys outside any section that name no option of
// ivoa-dataset itself are build's when build runs, so a detector settings
// file (stereo_detector.ini) relabels offline as it is. CLI11 reads a
// config file for the main app only, and would want them under [build].
class BuildKeysConfig : public CLI::ConfigINI {
 public:
  BuildKeysConfig(const CLI::App& app, const CLI::App& build) : app_(app), build_(build) {}
  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    std::vector<CLI::ConfigItem> items = CLI::ConfigINI::from_config(input);
    if (!build_.parsed()) return items;
    for (CLI::ConfigItem& item : items)
      if (item.parents.empty() && !app_.get_option_no_throw("--" + item.name)) item.parents = {build_.get_name()};
    return items;
  }

 private:
  const CLI::App& app_;
  const CLI::App& build_;
};

struct BuildCommand {
  CLI::App* command = nullptr;
  std::string out, session;
  std::vector<std::string> logs;
  dataset::BuildOptions options;
  bool no_evidence = false;
  std::vector<CLI::Option*> relabel_flags;  // the grid's and the detector's: they change offline labels only
};

void add_build_command(CLI::App& app, BuildCommand& b) {
  CLI::App* build = b.command = app.add_subcommand("build", "logs -> dataset sessions");
  build->fallthrough();  // --config and --log-level after "build" too
  app.config_formatter(std::make_shared<BuildKeysConfig>(app, *build));
  auto& options = b.options;
  build->add_option("--out", b.out, "dataset folder (created; sessions are added to it)")->required();
  build
      ->add_option("--labels", options.labels,
                   "'recorded' (the log's INTROSPECTION_LABELS) or a detector to re-run offline: jppc, dense")
      ->capture_default_str()
      ->check(CLI::IsMember(label_sources()));
  build->add_option("--session", b.session, "session name for all logs (default: per log, from the file name)");
  build
      ->add_option("--environment", options.environment,
                   "indoor or outdoor (default: what the simulator logged, else the scene name)")
      ->check(CLI::IsMember({"indoor", "outdoor"}));
  build
      ->add_option("--views", options.views,
                   "1: left patches (the paper); 2: each with the right image warped onto the ground plane below it")
      ->check(CLI::IsMember({1, 2}))
      ->capture_default_str();
  build
      ->add_option("--patch-scale", options.patch_scale,
                   "0: fixed --patch-size squares (the paper); k > 0: squares of k footprint-disc widths (at least "
                   "--patch-size) resized to --patch-size, so near cells show their whole disc")
      ->check(ivoa::non_negative_number())
      ->capture_default_str();
  build
      ->add_option("--keep-tn", options.keep_tn,
                   "store this fraction of the TN cells, the same ones on every rebuild (TN is about two thirds of "
                   "the cells; 0.25 saves about 45 % of the disk); keep 1 for test sessions, whose overall accuracy it "
                   "would skew")
      ->check(CLI::Validator(check_fraction, "in (0, 1]"))
      ->capture_default_str();
  build->add_flag("--no-evidence", b.no_evidence,
                  "do not store the detector's per-sample evidence (JPP-C's window costs, re-run on each frame; "
                  "ivoa-train learns them as a side task)");
  // Capped as the monitor's: utime arithmetic near 2^63 overflowed and paired nothing.
  build->add_option("--sync-tolerance-us", options.pairing.tolerance_us, "max |stereo - depth| utime, us")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 60e6));
  ivoa::add_log_channel_option(*build, "--stereo-channel", options.stereo_channel, "stereo pairs");
  ivoa::add_log_channel_option(*build, "--depth-channel", options.depth_channel, "depth images");
  ivoa::add_log_channel_option(*build, "--calibration-channel", options.calibration_channel, "the rig calibration");
  ivoa::add_log_channel_option(*build, "--labels-channel", options.labels_channel,
                               "the monitor's labels (--labels recorded)");
  ivoa::add_log_channel_option(*build, "--truth-channel", options.truth_channel, "the simulator's ground truth");
  build->add_option("logs", b.logs, "LCM log files, in order")->required()->check(ivoa::input_file());
  const size_t before_relabel_flags = build->get_options().size();
  add_query_grid_options(*build, options.grid);
  stereo::add_detector_options(*build, options.detector);
  b.relabel_flags = build->get_options();  // a copy: erase what came before
  b.relabel_flags.erase(b.relabel_flags.begin(), b.relabel_flags.begin() + static_cast<long>(before_relabel_flags));
}

// Checked before the first log is read: a bad value found at the first frame
// would not name its flag.
bool detector_flags_valid(const stereo::DetectorConfig& detector) {
  try {
    stereo::validate(detector.jpp);
    stereo::validate(detector.dense);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  return true;
}

// After parsing. Returns an exit code, or -1 to go on.
int finish_build_options(BuildCommand& b) {
  b.options.evidence = !b.no_evidence;
  if (b.options.labels != dataset::kRecordedLabels) return detector_flags_valid(b.options.detector) ? -1 : kExitUsage;
  const CLI::Option& patch_size = *b.command->get_option("--patch-size");
  if (const CLI::Option* flag = ignored_with_recorded_labels(b.relabel_flags, patch_size, b.options)) {
    spdlog::error(
        "{} does not apply to --labels recorded (the labels carry the grid and detector the live "
        "processes used); re-label offline with --labels jppc or dense to change them",
        flag->get_name());
    return kExitUsage;
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Build introspection datasets from LCM logs, and summarise them"};
  app.require_subcommand(1);
  CommonOptions common;
  add_offline_options(app, common);
  BuildCommand build;
  add_build_command(app, build);
  auto* info = app.add_subcommand("info", "sessions, class counts and splits of a dataset");
  info->fallthrough();  // --config and --log-level after "info" too
  std::string root, split;
  // Not ->required(): CLI11 would name only "--dataset" as missing.
  info->add_option("dataset,--dataset", root, "dataset folder: the argument, or --dataset as ivoa-train takes it")
      ->check(ivoa::input_folder());
  info->add_option("--split", split, "a split file to check against the dataset")->check(ivoa::input_file());

  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  init_logging("dataset", common.log_level);
  if (*info && root.empty()) {
    spdlog::error("info: which dataset? Give its folder: ivoa-dataset info DATASET (or --dataset DATASET)");
    return kExitUsage;
  }
  if (*build.command)
    if (const int code = finish_build_options(build); code >= 0) return code;
  try {
    if (*build.command) return run_build(build.out, build.session, build.logs, build.options);
    return run_info(root, split);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitBadInput;
  }
}
