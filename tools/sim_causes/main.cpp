// ivoa-sim-causes: why did the stereo detector fail? For simulated session
// logs with recorded labels, re-renders each frame with failures once as it
// was and once per stereo-failure phenomenon taken out of the scene, re-runs
// the detector on the failure cells, and writes which phenomena's removal
// makes each verdict right (causes.csv, joined by ivoa_report.py --causes).
// Each --variant (other settings of the same detector) is also run on the
// frames as they were: which failures it fixes (the CSV's fixed_by column)
// and, over every labelled cell of those frames, what it gets right and
// wrong (--variants-out).
//
//   ivoa-sim-causes --out causes.csv out/main-job-default/logs/*_s31.lcmlog
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "ivoa/causes/cause_finder.hpp"
#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/labels.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/progress.hpp"
#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/session_name.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo/options.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace fs = std::filesystem;
using namespace ivoa;

namespace {

using GT = sim_ground_truth_t;
using Labels = introspection_labels_t;

struct Options {
  std::string out;
  std::string scene_file;  // empty: <scene_dir>/<logged scene name>.yaml
  std::string scene_dir = IVOA_SIM_SCENES_DIR;
  causes::SessionTiming timing{/*start_utime=*/0, /*rate_hz=*/0, /*noise_seed=*/0};  // rate 0: from the log
  int64_t start_utime = -1;  // < 0: the utime of the logged frame with seq 0
  std::string dataset;       // failure cells from this dataset's sessions instead of the logs' labels
  stereo::DetectorConfig detector;
  std::vector<causes::DetectorVariant> variants;
  std::string variants_out;  // per session, variant and label: what each variant says (empty: not written)
  // The log's channels read (defaults: the simulator's and the monitor's own).
  std::string calibration_channel{channels::kRigCalibration};
  std::string truth_channel{channels::kSimGroundTruth};
  std::string labels_channel{channels::kIntrospectionLabels};
  std::string stereo_channel{channels::kStereoImages};
};

// JPP-C works on half-resolution images (JPP's 480x300): does it miss
// because of that? (For the dense detector: SGBM at full resolution, with
// the disparity range that still sees the ground as near.)
const char* const kDefaultVariant = "full resolution: --rect_scale 1 --sgbm_rect_scale 1 --sgbm_num_disparities 192";

// "NAME: FLAGS" -> the base config with FLAGS (the detector flags of this
// tool) applied and checked. Throws std::invalid_argument naming the variant.
causes::DetectorVariant parse_variant(const std::string& text, const stereo::DetectorConfig& base) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos)
    throw std::invalid_argument("--variant '" + text + "': expected 'NAME: FLAGS', e.g. '" + kDefaultVariant + "'");
  auto trim = [](std::string t) {
    t.erase(0, t.find_first_not_of(' '));
    t.erase(t.find_last_not_of(' ') + 1);
    return t;
  };
  causes::DetectorVariant v{trim(text.substr(0, colon)), base};
  causes::check_variant_name(v.name);
  CLI::App flags{"variant"};
  stereo::add_detector_options(flags, v.config);
  try {
    flags.parse(text.substr(colon + 1), false);
    stereo::validate(v.config.jpp);
    stereo::validate(v.config.dense);
  } catch (const std::exception& e) {  // CLI::ParseError or a bad value
    throw std::invalid_argument("--variant '" + text + "': " + e.what());
  }
  return v;
}

struct TruthFrame {
  std::string scene;
  int64_t seed = 0, seq = 0;
  sim::Pose2D pose;
};

// What the tool needs of one log: small messages only (no images kept).
struct SessionLog {
  std::optional<RigCalibration> rig;
  std::map<int64_t, TruthFrame> truth;  // by stereo utime
  std::vector<Labels> labels;
  // Per labels message, the grid cell of each entry where they are not the
  // whole grid in order (labels taken from a dataset); empty: the index.
  std::vector<std::vector<int32_t>> cell_ids;
  int32_t pixelformat = -1;
  int64_t bad_messages = 0;
  std::set<int64_t> labelled_utimes;
  int64_t repeated_labels = 0;  // a frame's labels again (a log given twice): skipped
};

void read_event(const logio::LogEvent& e, const Options& opt, bool want_labels, SessionLog& log) {
  bool ok = true;
  if (e.channel == opt.calibration_channel && !log.rig) {
    rig_calibration_t msg;
    if ((ok = logio::decode(e, msg))) log.rig = from_message(msg);
  } else if (e.channel == opt.truth_channel) {
    sim_ground_truth_t msg;
    if ((ok = logio::decode(e, msg))) {
      if (!std::isfinite(msg.robot_x) || !std::isfinite(msg.robot_y) || !std::isfinite(msg.robot_yaw))
        throw std::invalid_argument(fmt::format("ground truth at utime {}: robot pose ({}, {}, {})", msg.utime,
                                                msg.robot_x, msg.robot_y, msg.robot_yaw));
      log.truth[msg.utime] = {msg.scene, msg.seed, msg.seq, {msg.robot_x, msg.robot_y, msg.robot_yaw}};
    }
  } else if (e.channel == opt.labels_channel && want_labels) {
    Labels msg;
    if ((ok = logio::decode(e, msg))) {
      causes::check_labels(msg);
      if (!log.labelled_utimes.insert(msg.utime).second) ++log.repeated_labels;
      else log.labels.push_back(std::move(msg));
    }
  } else if (e.channel == opt.stereo_channel && log.pixelformat < 0) {
    stereo_image_t msg;
    if ((ok = logio::decode(e, msg))) log.pixelformat = msg.left.pixelformat;
  }
  if (!ok) {
    ++log.bad_messages;
    spdlog::warn("{} at byte {}: undecodable message, skipped", e.channel, e.offset);
  }
}

SessionLog read_log(const std::string& path, const Options& opt, bool want_labels) {
  logio::LogReader reader(path, {/*resync=*/true});  // damage skipped, reported below
  SessionLog log;
  logio::LogEvent event;
  while (reader.next(event)) {
    try {
      read_event(event, opt, want_labels, log);
    } catch (const std::exception& e) {  // e.g. an invalid calibration
      ++log.bad_messages;
      spdlog::warn("{}: {} at byte {}: {}", path, event.channel, event.offset, e.what());
    }
  }
  if (const std::string why = reader.not_a_log(); !why.empty()) throw std::runtime_error(path + ": " + why);
  for (const auto& p : reader.problems()) spdlog::warn("{}: byte {}: {}", path, p.offset, p.what);
  if (log.repeated_labels > 0)
    spdlog::warn("{}: {} frames' labels came again (a log given twice?): each frame explained once", path,
                 log.repeated_labels);
  if (!log.rig) throw std::runtime_error(path + ": no " + opt.calibration_channel + " message");
  if (log.truth.empty())
    throw std::runtime_error(path + ": no " + opt.truth_channel + " messages (causes need a simulated session)");
  if (want_labels && log.labels.empty()) throw std::runtime_error(path + ": no " + opt.labels_channel + " messages");
  // The frames are re-rendered in the recorded pixel format (JPEG rounds):
  // without it, "cannot encode unknown pixel format -1".
  if (log.pixelformat < 0)
    throw std::runtime_error(path + ": no decodable " + opt.stereo_channel +
                             " message (its pixel format says how to re-render the frames)");
  return log;
}

// The labelled cells of a dataset session (e.g. the dense detector's labels,
// made offline by ivoa-dataset), one labels message per frame.
void labels_from_dataset(const std::string& root, const std::string& session, SessionLog& log) {
  if (const auto sessions = dataset::list_sessions(root);
      std::find(sessions.begin(), sessions.end(), session) == sessions.end())
    throw std::runtime_error(fmt::format("dataset {} has no session {} (named after the log); it has: {}", root,
                                         session,
                                         sessions.empty() ? "none" : fmt::format("{}", fmt::join(sessions, ", "))));
  const dataset::SessionReader reader(root + "/" + session);
  const dataset::SessionInfo& info = reader.info();
  for (const dataset::SampleRecord& s : reader.samples()) {
    if (s.label == Labels::LABEL_NONE) continue;
    if (log.labels.empty() || log.labels.back().utime != s.utime) {
      Labels l{};  // lcm-gen types leave numbers uninitialised
      l.utime = s.utime;
      l.detector = info.detector;
      l.safety_radius = info.grid.safety_radius;
      log.labels.push_back(std::move(l));
      log.cell_ids.emplace_back();
    }
    Labels& l = log.labels.back();
    l.label.push_back(static_cast<int8_t>(s.label));
    l.stereo_state.push_back(static_cast<int8_t>(s.stereo_state));
    l.depth_state.push_back(static_cast<int8_t>(s.depth_state));
    l.x.push_back(s.x), l.y.push_back(s.y), l.u.push_back(s.u), l.v.push_back(s.v);
    l.num_cells = l.num_x = static_cast<int32_t>(l.label.size());  // the frame's labelled cells, as a 1 x n grid
    l.num_y = 1;
    log.cell_ids.back().push_back(s.cell);
  }
}

int64_t session_start(const SessionLog& log, const Options& opt, const std::string& path) {
  if (opt.start_utime >= 0) {
    // The frames are re-rendered from frame 0 on: frame 0 must be near them.
    const int64_t first = log.truth.begin()->first, last = log.truth.rbegin()->first;
    constexpr int64_t kOneDayUs = 86'400'000'000;
    if (opt.start_utime > first || last - opt.start_utime > kOneDayUs)
      throw std::runtime_error(fmt::format(
          "{}: --start-utime {} is not the session's first frame: the log's frames run from utime {} to {} (the "
          "driver's --start-utime, or leave it out when the log holds frame 0)",
          path, opt.start_utime, first, last));
    return opt.start_utime;
  }
  for (const auto& [utime, t] : log.truth)
    if (t.seq == 0) return utime;
  throw std::runtime_error(path +
                           ": the log does not start at the session's first frame (no seq 0); give --start-utime");
}

// The times of the frames the log holds, frame 0's and later ones.
std::vector<int64_t> frame_times(const SessionLog& log, int64_t start_utime) {
  std::vector<int64_t> times{start_utime};
  for (const auto& [utime, truth] : log.truth)
    if (utime > start_utime) times.push_back(utime);
  return times;
}

// Says when a --rate given cannot be the driver's (its frames' times are not
// whole periods of it), or may not be (they read as another rate): another
// rate gives other frame indices, so other noise, and verdicts go "not
// reproduced". Gaps all even numbers of periods read as half the rate.
void check_rate_given(const std::string& session, const SessionLog& log, const causes::SessionTiming& timing) {
  const std::vector<int64_t> times = frame_times(log, timing.start_utime);
  if (times.size() < 2) return;
  const double read = causes::rate_from_frame_times(times);
  if (!causes::frame_times_fit_rate(times, timing.rate_hz))
    spdlog::warn(
        "{}: --rate {:.6g}, but its frames' times are not whole periods of it (they read as {:.6g} Hz): "
        "is --rate the driver's?",
        session, timing.rate_hz, read);
  else if (std::abs(read - timing.rate_hz) > 1e-3 * timing.rate_hz)
    spdlog::info(
        "{}: --rate {:.6g}, and its frames' times read as {:.6g} Hz (every other frame missing, or "
        "another --rate?)",
        session, timing.rate_hz, read);
}

struct Tally {
  std::map<std::pair<int, std::string>, int64_t> by_label_and_cause;
  int64_t failures = 0, reproduced = 0, frames = 0, skipped_frames = 0, bad_messages = 0;
  // Per variant: what it says on the labelled cells, and how many of the
  // failures no phenomenon explains ("none found") it fixes, by label.
  std::vector<causes::VariantTally> variants;
  std::vector<std::array<int64_t, 4>> unexplained_fixed;
  std::array<int64_t, 4> unexplained{};

  void add(const Tally& o) {
    for (const auto& [key, count] : o.by_label_and_cause) by_label_and_cause[key] += count;
    failures += o.failures, reproduced += o.reproduced, frames += o.frames, skipped_frames += o.skipped_frames;
    bad_messages += o.bad_messages;
    for (size_t l = 0; l < 4; ++l) unexplained[l] += o.unexplained[l];
    // A session that stopped before its finder existed has no variant tallies.
    if (o.variants.empty()) return;
    variants.resize(o.variants.size()), unexplained_fixed.resize(o.variants.size());
    for (size_t v = 0; v < o.variants.size(); ++v)
      for (size_t l = 0; l < 4; ++l) {
        variants[v].cells[l] += o.variants[v].cells[l], variants[v].right[l] += o.variants[v].right[l];
        variants[v].wrong[l] += o.variants[v].wrong[l], unexplained_fixed[v][l] += o.unexplained_fixed[v][l];
      }
  }
};

// One session's CSV rows (written in the logs' order once all are done) and counts.
struct SessionResult {
  std::ostringstream rows, variant_rows;
  Tally tally;
  std::string error;  // the session could not be explained at all
};

void write_rows(std::ostream& csv, const std::string& session, const Labels& labels,
                const std::vector<int32_t>& cell_ids, const std::vector<causes::CellCause>& cells,
                const std::vector<causes::DetectorVariant>& variants, Tally& tally) {
  for (const auto& c : cells) {
    const auto i = static_cast<size_t>(c.cell);
    csv << session << ',' << labels.detector << ',' << labels.utime << ',' << (cell_ids.empty() ? c.cell : cell_ids[i])
        << ',' << (c.label == Labels::LABEL_FP ? "FP" : "FN") << ',' << labels.x[i] << ',' << labels.y[i] << ','
        << int{c.stereo_state} << ',' << int{c.replayed_state} << ',' << int{c.tested} << ',' << int{c.causes} << ','
        << int{c.jointly} << ",\"" << causes::describe(c) << "\"," << causes::variant_names(variants, c.fixed_by)
        << '\n';
    ++tally.failures;
    tally.reproduced += c.reproduced();
    ++tally.by_label_and_cause[{c.label, causes::describe(c)}];
    if (c.reproduced() && !c.causes && !c.jointly) {
      const auto l = static_cast<size_t>(c.label);
      ++tally.unexplained[l];
      for (size_t v = 0; v < variants.size(); ++v) tally.unexplained_fixed[v][l] += (c.fixed_by >> v) & 1u;
    }
  }
}

void write_variant_rows(std::ostream& csv, const std::string& session, const std::string& detector,
                        const std::vector<causes::DetectorVariant>& variants,
                        const std::vector<causes::VariantTally>& tallies) {
  for (size_t v = 0; v < variants.size(); ++v)
    for (size_t l = 0; l < 4; ++l)
      csv << session << ',' << detector << ',' << variants[v].name << ',' << kLabelNames[l] << ','
          << tallies[v].cells[l] << ',' << tallies[v].right[l] << ',' << tallies[v].wrong[l] << '\n';
}

void explain_session(const std::string& path, const Options& opt, SessionResult& out) {
  const std::string session = logio::session_name_of(path);
  SessionLog log = read_log(path, opt, opt.dataset.empty());
  if (!opt.dataset.empty()) labels_from_dataset(opt.dataset, session, log);
  out.tally.bad_messages = log.bad_messages;
  if (log.labels.empty()) {  // a dataset session without labelled cells: nothing to explain
    spdlog::info("{}: no labelled cells", session);
    return;
  }
  const TruthFrame& first = log.truth.begin()->second;
  const std::string scene_file = opt.scene_file.empty() ? opt.scene_dir + "/" + first.scene + ".yaml" : opt.scene_file;
  sim::SceneSpec scene = sim::load_scene_spec(scene_file);
  if (scene.name != first.scene)
    throw std::runtime_error(
        fmt::format("{}: the log's scene is '{}', {} is '{}'", path, first.scene, scene_file, scene.name));
  causes::SessionTiming timing = opt.timing;
  timing.start_utime = session_start(log, opt, path);
  if (timing.rate_hz == 0) {
    timing.rate_hz = causes::rate_from_frame_times(frame_times(log, timing.start_utime));
    spdlog::info("{}: recorded at {:.6g} Hz", session, timing.rate_hz);
  } else {
    check_rate_given(session, log, timing);
  }
  causes::CauseFinder finder(scene, static_cast<uint64_t>(first.seed), *log.rig, timing, log.labels.front().detector,
                             opt.detector, opt.variants);
  out.tally.unexplained_fixed.resize(opt.variants.size());
  Progress progress(session + " (" + causes::phenomena_names(finder.testable()) + ")",
                    static_cast<double>(log.labels.size()), "frames", 20.0);
  int64_t not_replayed = 0;  // frames the trajectory does not reach at the rate used
  for (size_t f = 0; f < log.labels.size(); ++f) {
    const Labels& labels = log.labels[f];
    const auto truth = log.truth.find(labels.utime);
    if (truth == log.truth.end()) {
      ++out.tally.skipped_frames;
      spdlog::warn("{}: labels at {} have no ground-truth frame, skipped", session, labels.utime);
      continue;
    }
    try {
      static const std::vector<int32_t> kGridOrder;  // recorded labels: entry i is cell i
      const std::vector<int32_t>& cell_ids = log.cell_ids.empty() ? kGridOrder : log.cell_ids[f];
      write_rows(out.rows, session, labels, cell_ids, finder.explain(labels, truth->second.pose, log.pixelformat),
                 opt.variants, out.tally);
      ++out.tally.frames;
    } catch (const causes::ReplayError& e) {
      ++out.tally.skipped_frames;
      ++not_replayed;
      spdlog::warn("{}: {}", session, e.what());
    }
    progress.update(static_cast<double>(f + 1));
  }
  progress.finish();
  // A real-time recording whose simulator dropped frames has frame times
  // that suggest too low a rate; most frames then miss their poses.
  if (opt.timing.rate_hz == 0 && 2 * not_replayed > static_cast<int64_t>(log.labels.size()))
    spdlog::warn(
        "{}: {} of {} frames were not replayed at {:.6g} Hz, the rate read from the frames' times (which a "
        "simulator that dropped frames leaves uneven): give the driver's --rate",
        session, not_replayed, log.labels.size(), timing.rate_hz);
  out.tally.variants = finder.variant_tallies();
  write_variant_rows(out.variant_rows, session, log.labels.front().detector, opt.variants, out.tally.variants);
}

// Sessions on `jobs` threads (each renders on one core); results by log index.
std::vector<SessionResult> explain_sessions(const std::vector<std::string>& logs, const Options& opt, int jobs) {
  std::vector<SessionResult> results(logs.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i; (i = next++) < logs.size();) {
      try {
        explain_session(logs[i], opt, results[i]);
      } catch (const std::exception& e) {
        results[i].error = e.what();
      }
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::max(1, std::min<int>(jobs, static_cast<int>(logs.size()))); ++j)
    threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  return results;
}

double percent(int64_t part, int64_t whole) {
  return whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

// Per variant: the failures it fixes (all, and those no phenomenon explains)
// and the price: the right verdicts it turns wrong.
void print_variants(const Tally& t, const std::vector<causes::DetectorVariant>& variants) {
  for (size_t v = 0; v < variants.size(); ++v) {
    const causes::VariantTally& c = t.variants[v];
    std::printf("with '%s', on the same frames:\n", variants[v].name.c_str());
    for (const int l : {Labels::LABEL_FP, Labels::LABEL_FN})
      std::printf("  fixes %5.1f %% of the %s (%lld), %5.1f %% of those with no cause found (%lld)\n",
                  percent(c.right[l], c.cells[l]), kLabelNames[l], static_cast<long long>(c.cells[l]),
                  percent(t.unexplained_fixed[v][l], t.unexplained[l]), static_cast<long long>(t.unexplained[l]));
    for (const int l : {Labels::LABEL_TP, Labels::LABEL_TN})
      std::printf("  gets wrong %5.1f %% of the %s (%lld)\n", percent(c.wrong[l], c.cells[l]), kLabelNames[l],
                  static_cast<long long>(c.cells[l]));
  }
}

void print_summary(const Tally& t) {
  std::printf(
      "%lld failure cells in %lld frames (%lld frames skipped); re-rendered verdict matches the recorded one "
      "for %lld (%.1f %%)\n",
      static_cast<long long>(t.failures), static_cast<long long>(t.frames), static_cast<long long>(t.skipped_frames),
      static_cast<long long>(t.reproduced),
      t.failures ? 100.0 * static_cast<double>(t.reproduced) / static_cast<double>(t.failures) : 0.0);
  if (t.bad_messages > 0) std::printf("%lld undecodable messages skipped\n", static_cast<long long>(t.bad_messages));
  for (const int label : {Labels::LABEL_FP, Labels::LABEL_FN}) {
    int64_t n = 0;
    for (const auto& [key, count] : t.by_label_and_cause) n += key.first == label ? count : 0;
    std::printf("%s (%lld), fixed by removing:\n", label == Labels::LABEL_FP ? "FP" : "FN", static_cast<long long>(n));
    for (const auto& [key, count] : t.by_label_and_cause)
      if (key.first == label)
        std::printf("  %-48s %7lld  %5.1f %%\n", key.second.c_str(), static_cast<long long>(count),
                    100.0 * static_cast<double>(count) / static_cast<double>(n));
  }
}

struct CommandLine {
  Options opt;
  std::vector<std::string> logs;
  int jobs = 1;
  std::vector<std::string> variants{kDefaultVariant};
  bool no_variants = false;
};

void add_options(CLI::App& app, CommandLine& cl) {
  Options& opt = cl.opt;
  app.add_option("--out", opt.out, "CSV to write: one row per FP/FN cell (session, utime, cell, ..., causes)")
      ->required();
  app.add_option("--scene", opt.scene_file, "scene file (default: <scene-dir>/<the logged scene name>.yaml)")
      ->check(ivoa::input_file());
  app.add_option("--scene-dir", opt.scene_dir, "where the logged scenes' files are")->capture_default_str();
  app.add_option("--rate", opt.timing.rate_hz,
                 "the simulator driver's --rate (frames per second of session time; default: from the frames' times)")
      ->check(ivoa::number_in(0.01, 1000.0));  // the driver's range
  app.add_option("--noise-seed", opt.timing.noise_seed, "the simulator driver's --noise-seed")->capture_default_str();
  app.add_option("--start-utime", opt.start_utime,
                 "utime of the session's frame 0 (default: the logged frame with seq 0)")
      ->check(ivoa::non_negative_number());  // negative is the struct's "not given"
  app.add_option("--dataset", opt.dataset,
                 "take the failure cells from this dataset's sessions (named like the logs) instead of the logs' "
                 "labels: e.g. the dense detector's, labelled offline by ivoa-dataset")
      ->check(ivoa::input_folder());
  app.add_option("logs", cl.logs, "simulated session logs with recorded INTROSPECTION_LABELS, one session each")
      ->required()
      ->check(ivoa::input_file());
  app.add_option("--jobs", cl.jobs, "sessions explained at once (each on one core)")
      ->check(ivoa::positive_number())
      ->capture_default_str();
  app.add_option("--variant", cl.variants,
                 "other settings of the detector to try on the frames as they were, 'NAME: FLAGS' (the detector "
                 "flags below, applied over this run's); repeat for several (at most 8)")
      ->capture_default_str()
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);  // one value per --variant: logs after it stay positional
  app.add_flag("--no-variants", cl.no_variants, "try no other settings");
  app.add_option("--variants-out", opt.variants_out,
                 "CSV to write: per session, variant and label, the labelled cells of the re-rendered frames and how "
                 "many the variant gets right and wrong");
  add_log_channel_option(app, "--calibration-channel", opt.calibration_channel, "the rig calibration");
  add_log_channel_option(app, "--truth-channel", opt.truth_channel, "the simulator's ground truth");
  add_log_channel_option(app, "--labels-channel", opt.labels_channel, "the monitor's labels (without --dataset)");
  add_log_channel_option(app, "--stereo-channel", opt.stereo_channel, "stereo pairs (their pixel format)");
  stereo::add_detector_options(app, opt.detector);
}

// Throws std::invalid_argument naming the --variant at fault.
void parse_variants(CommandLine& cl) {
  if (cl.no_variants) return;
  auto& parsed = cl.opt.variants;
  for (const std::string& v : cl.variants) {
    parsed.push_back(parse_variant(v, cl.opt.detector));
    for (size_t i = 0; i + 1 < parsed.size(); ++i)
      if (parsed[i].name == parsed.back().name)
        throw std::invalid_argument("--variant '" + v + "': the name is already used");
  }
  if (parsed.size() > 8) throw std::invalid_argument("at most 8 --variant");
}

// Whether the outputs can be written, found before the work; false, having
// said why, if not.
bool outputs_writable(const Options& opt) {
  for (const std::string& out : {opt.out, opt.variants_out})
    if (const std::string why = why_cannot_write(out); !why.empty()) {
      spdlog::error("cannot write {}: {}", out, why);
      return false;
    }
  return true;
}

// The two CSVs, whole or not at all: an earlier run's stay as they were
// when this one fails, or explains nothing.
bool write_outputs(const Options& opt, const std::string& rows, const std::string& variant_rows) {
  FileSet files;
  std::string error;
  const bool written =
      files.stage(opt.out,
                  "session,detector,utime,cell,label,x,y,stereo_state,replayed_state,tested,causes,jointly,cause,"
                  "fixed_by\n" +
                      rows,
                  error) &&
      (opt.variants_out.empty() ||
       files.stage(opt.variants_out, "session,detector,variant,label,cells,right,wrong\n" + variant_rows, error)) &&
      files.commit(error);
  if (!written) spdlog::error("{}", error);
  return written;
}

// Two logs of one session name would give its rows twice (and a variants
// file the report refuses): said before any work.
bool sessions_named_once(const std::vector<std::string>& logs) {
  std::map<std::string, std::string> log_of;
  for (const auto& log : logs) {
    const auto [it, added] = log_of.emplace(logio::session_name_of(log), log);
    if (!added) {
      spdlog::error(
          "{} and {} are both session {}: give each session's log once (split files: join them first, "
          "cat NAME.lcmlog.[0-9][0-9] > NAME.lcmlog)",
          it->second, log, it->first);
      return false;
    }
  }
  return true;
}

// An output that is one of the inputs (a log, a file of the dataset or of
// the scenes) or the other output would be truncated before it is read:
// said before anything is opened.
bool outputs_apart_from_inputs(const CommandLine& cl) {
  std::vector<std::string> inputs = cl.logs;
  for (const std::string& input : {cl.opt.dataset, cl.opt.scene_file.empty() ? cl.opt.scene_dir : cl.opt.scene_file})
    if (!input.empty()) inputs.push_back(input);
  for (const std::string* out : {&cl.opt.out, &cl.opt.variants_out})
    for (const std::string& input : inputs)
      if (writes_over(*out, input)) {
        spdlog::error("{} is the input {} (or a file in it): it would be written over", *out, input);
        return false;
      }
  if (writes_over(cl.opt.variants_out, cl.opt.out)) {
    spdlog::error("--out {} and --variants-out {} are the same file", cl.opt.out, cl.opt.variants_out);
    return false;
  }
  return true;
}

int explain(const CommandLine& cl) {
  const Options& opt = cl.opt;
  if (!sessions_named_once(cl.logs) || !outputs_apart_from_inputs(cl)) return kExitUsage;
  if (!outputs_writable(opt)) return kExitIoError;
  Tally tally;
  tally.unexplained_fixed.resize(opt.variants.size());
  tally.variants.resize(opt.variants.size());
  int worst = kExitOk;
  size_t failed = 0;
  const std::vector<SessionResult> results = explain_sessions(cl.logs, opt, cl.jobs);
  std::string rows, variant_rows;
  for (const SessionResult& r : results) {
    rows += r.rows.str();
    variant_rows += r.variant_rows.str();
    tally.add(r.tally);
    if (!r.error.empty()) {  // a bad session is reported and skipped; the others are still written
      spdlog::error("{}", r.error);
      worst = kExitBadInput;
      ++failed;
    }
  }
  if (failed == results.size()) return worst;  // no session explained: no tables of zeros, no files
  if (tally.frames == 0 && tally.skipped_frames > 0) {
    // Every frame refused (warnings above): an empty table is not a result.
    spdlog::error("no frame could be replayed: all {} were skipped (warnings above)", tally.skipped_frames);
    return kExitBadInput;
  }
  if (!write_outputs(opt, rows, variant_rows)) return kExitIoError;
  print_summary(tally);
  print_variants(tally, opt.variants);
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Failure causes on simulated logs: re-render each failure without each phenomenon and re-run the detector"};
  CommonOptions common;
  add_offline_options(app, common);
  CommandLine cl;
  add_options(app, cl);
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  init_logging("sim-causes", common.log_level);
  try {  // the detector's settings before minutes of reading logs (a bad one was exit 3 after them)
    stereo::validate(cl.opt.detector.jpp);
    stereo::validate(cl.opt.detector.dense);
    parse_variants(cl);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  return explain(cl);
}
