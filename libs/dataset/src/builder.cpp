#include "ivoa/dataset/builder.hpp"

#include <algorithm>
#include <deque>
#include <limits>
#include <filesystem>
#include <map>
#include <set>
#include <optional>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/dataset/patch.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/monitor/labeler.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo/detector.hpp"

namespace ivoa::dataset {
namespace {

// Frames kept while their labels may still come: the labels of a frame
// follow it within a few frames (detector and monitor latency).
constexpr size_t kMaxCachedFrames = 90;

struct Truth {
  cv::Mat phenomena, surface;
};

// Whether the TN cell `cell` of the frame at `utime` is stored when a
// fraction `keep` of TN cells is: a hash (splitmix64) of both, so the same
// log always keeps the same cells.
bool keeps_tn(int64_t utime, size_t cell, double keep) {
  if (keep >= 1) return true;
  uint64_t z = static_cast<uint64_t>(utime) * 0x9E3779B97F4A7C15ull + cell + 1;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53 < keep;
}

std::string environment_of(const std::string& scene) {
  if (scene.rfind("indoor", 0) == 0) return "indoor";
  if (scene.rfind("outdoor", 0) == 0) return "outdoor";
  return "unknown";
}

template <class Map>
void trim(Map& m, size_t max) {
  while (m.size() > max) m.erase(m.begin());
}

}  // namespace

struct SessionBuilder::Impl {
  std::string root, session;
  BuildOptions options;
  BuildReport report;
  std::unique_ptr<SessionWriter> writer;
  SessionInfo info;

  CalibrationChanges calibrations;
  std::optional<RigCalibration> rig;
  std::unique_ptr<stereo::ObstacleDetector> detector;
  std::unique_ptr<monitor::LabelingPipeline> pipeline;

  std::unique_ptr<GroundWarp> warp;         // views == 2
  std::map<int64_t, cv::Mat> left_images;   // utime -> raw left BGR (views == 2: the warped right view below it)
  std::map<int64_t, cv::Mat> right_images;  // utime -> raw right BGR, for evidence
  std::unique_ptr<stereo::ObstacleDetector> evidence_detector;  // made for the labels' detector when first needed
  bool evidence_warned = false;
  std::map<int64_t, Truth> truths;                           // utime -> simulator truth
  std::deque<introspection_labels_t> ready;                  // labels waiting for their frame's truth
  std::set<int64_t> stored_frames;                           // utimes: a frame's samples are stored once
  std::vector<std::pair<cv::Size, int64_t>> frames_by_size;  // stereo frames read, by left image size, in order
  int64_t label_sources = 0;  // messages the labels come from: recorded labels, or depth to re-label with

  bool rerun() const { return options.labels != kRecordedLabels; }
  void bad(const std::string& what);
  void on_calibration(const logio::LogEvent& e);
  void on_stereo(const logio::LogEvent& e);
  void on_depth(const logio::LogEvent& e);
  void on_labels(const logio::LogEvent& e);
  void on_truth(const logio::LogEvent& e);
  void take(std::vector<monitor::PipelineOutcome> outcomes);
  void emit_ready(bool all);
  void emit(const introspection_labels_t& labels);
  std::vector<std::vector<float>> evidence_of(const introspection_labels_t& labels, const cv::Mat& views);
  std::vector<int> patch_sides(const introspection_labels_t& labels, const cv::Mat& views) const;
  std::vector<std::pair<size_t, cv::Mat>> labelled_patches(const introspection_labels_t& labels, const cv::Mat& views,
                                                           const std::vector<int>& sides) const;
  void open_writer();
  void set_image_size(cv::Size size);
  void count_frames_of_other_sizes();
  std::string logs_read() const;  // "a.lcmlog, b.lcmlog", for messages
  std::string no_label_source() const;
  std::string no_samples() const;
  bool replaces_samples() const;
};

void SessionBuilder::Impl::bad(const std::string& what) {
  ++report.bad_messages;
  if (report.problems.size() < 100) report.problems.push_back(what);
  spdlog::warn("skipped: {}", what);
}

std::string SessionBuilder::Impl::logs_read() const {
  std::string logs;
  for (const auto& log : info.logs) logs += (logs.empty() ? "" : ", ") + log;
  return logs;
}

// Why a session whose logs hold nothing to label from, or no stereo frame
// to cut patches from, is refused, before an existing session of that name
// is replaced by an empty one.
std::string SessionBuilder::Impl::no_label_source() const {
  const std::string logs = logs_read();
  const std::string kept = "; session '" + session + "' not written (an existing one is kept)";
  if (report.stereo_frames == 0)
    return logs + ": no " + options.stereo_channel + " message after the calibration: no images to cut patches " +
           "from (recorded without the stereo camera, with -c leaving it out, or under another name: "
           "--stereo-channel?)" +
           kept;
  if (rerun())
    return logs + ": no " + options.depth_channel + " message after the calibration, so the depth monitor has " +
           "nothing to label from" + kept;
  return logs + ": no " + options.labels_channel + " message after the calibration: recorded without the depth " +
         "monitor? Label it offline from its depth frames with --labels jppc (or dense)" + kept;
}

// Whether a session of this name with samples is there to be replaced.
bool SessionBuilder::Impl::replaces_samples() const {
  try {
    return SessionReader(root + "/" + session).size() > 0;
  } catch (const std::exception&) {
    return false;  // none, or one that cannot be read: replaced as before
  }
}

// Why logs gave no sample at all where that is an error: nothing paired
// (a --sync-tolerance-us too tight), or a session of the name with samples
// would be replaced by an empty one (it was, exit 0). A session whose frames
// paired but hold no cell the detector judged is written empty.
std::string SessionBuilder::Impl::no_samples() const {
  std::string why = fmt::format("{} of {} stereo frames labelled", report.frames_labelled, report.stereo_frames);
  if (report.frames_unmatched > 0)
    why += fmt::format(", {} without a depth frame within {:.1f} ms (--sync-tolerance-us)", report.frames_unmatched,
                       static_cast<double>(options.pairing.tolerance_us) / 1e3);
  if (report.patches_outside > 0) why += fmt::format(", {} cells whose patch leaves the image", report.patches_outside);
  if (report.tn_dropped > 0) why += fmt::format(", {} TN cells left out (--keep-tn)", report.tn_dropped);
  return logs_read() + ": no sample to store (" + why + "); session '" + session +
         "' not written (an existing one is kept)";
}

void SessionBuilder::Impl::open_writer() {
  if (writer) return;
  info.patch_size = rerun() ? options.grid.patch_size : info.patch_size;
  info.views = options.views;
  info.patch_scale = options.patch_scale;
  info.tn_kept = options.keep_tn;
  // The user's word first, then the simulator's, then the scene name's.
  if (!options.environment.empty()) info.environment = options.environment;
  else if (info.environment.empty() || info.environment == "unknown") info.environment = environment_of(info.scene);
  writer = std::make_unique<SessionWriter>(root, info);
}

// The size of the left images the session's patches are cut from: its
// first stored frame's (session.json records it before any sample).
void SessionBuilder::Impl::set_image_size(cv::Size size) { report.image_size = info.image_size = size; }

// Stereo frames of another size than the session's, stored or not: a second
// camera's logs built into the same session.
void SessionBuilder::Impl::count_frames_of_other_sizes() {
  report.frames_other_size = 0;
  for (const auto& [size, frames] : frames_by_size)
    if (size != info.image_size) report.frames_other_size += frames;
}

void SessionBuilder::Impl::on_calibration(const logio::LogEvent& e) {
  rig_calibration_t msg;
  if (!logio::decode(e, msg))
    return bad(e.channel + " at byte " + std::to_string(e.offset) +
               ": does not decode as ivoa.rig_calibration_t (another type, truncated or damaged)");
  try {
    std::optional<RigCalibration> new_rig = calibrations.take_if_new(msg);
    if (!new_rig) return;
    rig = std::move(new_rig);
  } catch (const CalibrationError& err) {
    return bad(std::string("unusable calibration: ") + err.what());
  }
  info.rig_name = rig->rig_name;
  if (options.views == 2) warp = std::make_unique<GroundWarp>(*rig);
  evidence_detector.reset();  // remade for the new rig
  if (rerun()) {
    if (pipeline) take(pipeline->flush());
    detector = stereo::make_detector(options.labels, *rig, options.detector);
    pipeline = std::make_unique<monitor::LabelingPipeline>(*rig, options.grid, options.monitor, options.pairing);
  }
}

void SessionBuilder::Impl::on_stereo(const logio::LogEvent& e) {
  stereo_image_t msg;
  if (!logio::decode(e, msg))
    return bad(e.channel + " at byte " + std::to_string(e.offset) +
               ": does not decode as ivoa.stereo_image_t (another type, truncated or damaged)");
  if (const std::string why = stereo_times_error(msg); !why.empty())
    return bad(e.channel + " at byte " + std::to_string(e.offset) + ": stereo frame " + std::to_string(msg.utime) +
               ": " + why);
  ++report.stereo_frames;
  try {
    cv::Mat left = decode_image(msg.left);
    if (frames_by_size.empty() || frames_by_size.back().first != left.size())
      frames_by_size.push_back({left.size(), 0});
    ++frames_by_size.back().second;
    const cv::Mat right = rerun() || warp || options.evidence ? decode_image(msg.right) : cv::Mat();
    if (options.evidence) right_images[msg.utime] = right;
    cv::Mat views = warp ? warp->stack(left, right) : left;
    if (rerun()) {
      if (!detector) return bad("stereo frame " + std::to_string(msg.utime) + " before any calibration");
      detector->set_frame(left, right);
      obstacle_grid_t grid = make_obstacle_grid(pipeline->grid(), detector->name(), msg.utime);
      detector->evaluate(pipeline->grid(), grid);
      left_images[msg.utime] = std::move(views);
      take(pipeline->add_stereo(std::move(grid)));
    } else {
      left_images[msg.utime] = std::move(views);
    }
  } catch (const std::exception& err) {
    return bad("stereo frame " + std::to_string(msg.utime) + ": " + err.what());
  }
  trim(left_images, kMaxCachedFrames);
  trim(right_images, kMaxCachedFrames);
  emit_ready(false);
}

void SessionBuilder::Impl::on_depth(const logio::LogEvent& e) {
  if (!rerun()) return;
  ++label_sources;
  depth_image_t msg;
  if (!logio::decode(e, msg))
    return bad(e.channel + " at byte " + std::to_string(e.offset) +
               ": does not decode as ivoa.depth_image_t (another type, truncated or damaged)");
  if (!pipeline) return bad("depth frame " + std::to_string(msg.utime) + " before any calibration");
  try {
    cv::Mat depth = decode_depth(msg);
    if (cv::countNonZero(depth) == 0) return bad("depth frame " + std::to_string(msg.utime) + ": zero-filled");
    take(pipeline->add_depth(msg.utime, std::move(depth)));
  } catch (const std::exception& err) {
    bad("depth frame " + std::to_string(msg.utime) + ": " + err.what());
  }
}

namespace {

// What in a recorded labels message the session could not store (empty:
// nothing). A session of such messages was written unreadable, or one
// message ended the whole build.
std::string unstorable(const introspection_labels_t& m) {
  if (m.patch_size < 1 || m.patch_size > 4096) return "patch_size " + std::to_string(m.patch_size) + " is not 1-4096";
  return labels_content_error(m);
}

}  // namespace

void SessionBuilder::Impl::on_labels(const logio::LogEvent& e) {
  if (rerun()) return;
  ++label_sources;
  introspection_labels_t msg;
  if (!logio::decode(e, msg))
    return bad(e.channel + " at byte " + std::to_string(e.offset) +
               ": does not decode as ivoa.introspection_labels_t (another type, truncated or damaged)");
  if (const std::string why = unstorable(msg); !why.empty())
    return bad(e.channel + " at byte " + std::to_string(e.offset) + ": " + why + ", skipped");
  if (info.detector.empty()) {
    info.detector = msg.detector;
    info.grid = geometry_of(msg);
    info.patch_size = options.recorded_patch_size > 0 ? options.recorded_patch_size : msg.patch_size;
  } else if (msg.detector != info.detector) {
    return bad("labels for detector '" + msg.detector + "' in a session labelled for '" + info.detector + "'");
  }
  ready.push_back(std::move(msg));
}

void SessionBuilder::Impl::on_truth(const logio::LogEvent& e) {
  sim_ground_truth_t msg;
  if (!logio::decode(e, msg))
    return bad(e.channel + " at byte " + std::to_string(e.offset) +
               ": does not decode as ivoa.sim_ground_truth_t (another type, truncated or damaged)");
  if (info.scene.empty()) {
    info.scene = msg.scene;
    info.seed = msg.seed;
    info.environment = msg.environment.empty() ? "unknown" : msg.environment;
  }
  try {
    truths[msg.utime] = {decode_image(msg.phenomena, ColorOutput::kGray),
                         decode_image(msg.surface, ColorOutput::kGray)};
  } catch (const ImageError& err) {
    return bad("truth " + std::to_string(msg.utime) + ": " + err.what());
  }
  trim(truths, kMaxCachedFrames);
}

void SessionBuilder::Impl::take(std::vector<monitor::PipelineOutcome> outcomes) {
  for (auto& o : outcomes) {
    if (!o.labeled) {
      ++report.frames_unmatched;
      continue;
    }
    ready.push_back(std::move(o.labeled->labels));
  }
}

// A frame's labels are emitted once a newer stereo frame has been read (its
// truth, published with it, is in by then) or at the end of the session.
void SessionBuilder::Impl::emit_ready(bool all) {
  const int64_t newest = left_images.empty() ? 0 : left_images.rbegin()->first;
  while (!ready.empty() && (all || ready.front().utime < newest)) {
    emit(ready.front());
    ready.pop_front();
  }
}

// The side of the square cut around each cell of `labels` in `views` (the
// stacked model input): info.patch_size, or footprint-scaled.
std::vector<int> SessionBuilder::Impl::patch_sides(const introspection_labels_t& labels, const cv::Mat& views) const {
  const cv::Size image(views.cols, views.rows / info.views);
  return footprint_patch_sides(labels, info.patch_size, image, options.patch_scale);
}

// Each labelled cell of `labels` with its patch (empty where the square
// leaves the image), all cut at once (see cut_patches).
std::vector<std::pair<size_t, cv::Mat>> SessionBuilder::Impl::labelled_patches(const introspection_labels_t& labels,
                                                                               const cv::Mat& views,
                                                                               const std::vector<int>& sides) const {
  std::vector<size_t> cells;
  std::vector<PatchSquare> squares;
  for (size_t i = 0; i < labels.label.size(); ++i)
    if (labels.label[i] != introspection_labels_t::LABEL_NONE) {
      cells.push_back(i);
      squares.push_back({labels.u[i], labels.v[i], sides[i]});
    }
  const std::vector<cv::Mat> patches = cut_patches(views, info.views, squares, info.patch_size);
  std::vector<std::pair<size_t, cv::Mat>> out;
  for (size_t k = 0; k < cells.size(); ++k) out.emplace_back(cells[k], patches[k]);
  return out;
}

void SessionBuilder::Impl::emit(const introspection_labels_t& labels) {
  if (stored_frames.count(labels.utime)) {
    ++report.frames_repeated;
    return;
  }
  const auto image = left_images.find(labels.utime);
  if (image == left_images.end()) {
    return bad("labels for frame " + std::to_string(labels.utime) + " whose stereo images are not in the log");
  }
  const std::vector<std::vector<float>> evidence = evidence_of(labels, image->second);
  if (!writer) set_image_size(cv::Size(image->second.cols, image->second.rows / options.views));
  open_writer();
  const auto truth = truths.find(labels.utime);
  int32_t labelled = 0;
  for (int8_t l : labels.label) labelled += l != introspection_labels_t::LABEL_NONE;
  const int64_t frame = writer->add_frame(labels.utime, labels.depth_utime, labelled);
  stored_frames.insert(labels.utime);
  int64_t samples = 0;
  const std::vector<int> sides = patch_sides(labels, image->second);
  for (const auto& [i, patch] : labelled_patches(labels, image->second, sides)) {
    if (patch.empty()) {  // the patch would leave the image
      ++report.patches_outside;
      continue;
    }
    if (labels.label[i] == introspection_labels_t::LABEL_TN && !keeps_tn(labels.utime, i, options.keep_tn)) {
      writer->count_dropped_tn();  // only cells that would have been stored count as left out
      ++report.tn_dropped;
      continue;
    }
    SampleRecord s;
    s.frame = frame;
    s.utime = labels.utime;
    s.depth_utime = labels.depth_utime;
    s.cell = static_cast<int32_t>(i);
    s.label = labels.label[i];
    s.stereo_state = labels.stereo_state[i];
    s.depth_state = labels.depth_state[i];
    s.x = labels.x[i];
    s.y = labels.y[i];
    s.u = labels.u[i];
    s.v = labels.v[i];
    s.patch_side = sides[i];
    if (truth != truths.end()) {
      const PatchTruth t = summarize_truth(truth->second.phenomena, truth->second.surface, s.u, s.v, sides[i]);
      s.phenomena = t.phenomena;
      s.phenomenon = t.phenomenon;
      s.surface = t.surface;
    }
    writer->add_sample(s, patch, evidence.empty() ? std::vector<float>{} : evidence[i]);
    ++report.class_counts[static_cast<size_t>(s.label)];
    ++samples;
  }
  report.samples += samples;
  report.frames_labelled += samples > 0;
}

// Per cell of `labels`, the re-run detector's evidence (empty for unlabelled
// cells; NaN where its verdict is not the recorded one, or the frame's right
// image is gone). The first frame sets info.evidence_size; nothing when the
// session stores no evidence.
std::vector<std::vector<float>> SessionBuilder::Impl::evidence_of(const introspection_labels_t& labels,
                                                                  const cv::Mat& views) {
  if (!options.evidence || !rig || (writer && info.evidence_size == 0)) return {};
  if (!evidence_detector) {
    try {
      evidence_detector = stereo::make_detector(labels.detector, *rig, options.detector);
    } catch (const std::invalid_argument& e) {
      spdlog::warn("no evidence for detector '{}': {}", labels.detector, e.what());
      options.evidence = false;
      return {};
    }
  }
  const auto right = right_images.find(labels.utime);
  if (right != right_images.end())
    evidence_detector->set_frame(views.rowRange(0, views.rows / options.views), right->second);
  std::vector<std::vector<float>> out(labels.label.size());
  for (size_t i = 0; i < labels.label.size(); ++i) {
    if (labels.label[i] == introspection_labels_t::LABEL_NONE) continue;
    if (right == right_images.end()) {
      out[i].assign(static_cast<size_t>(info.evidence_size), std::numeric_limits<float>::quiet_NaN());
      continue;
    }
    stereo::Evidence e = evidence_detector->evidence(labels.x[i], labels.y[i], labels.safety_radius);
    if (!writer && info.evidence_size == 0) info.evidence_size = static_cast<int>(e.values.size());
    if (info.evidence_size == 0) return {};  // this detector keeps none
    if (static_cast<int>(e.values.size()) != info.evidence_size)
      throw DatasetError(fmt::format("frame {}: {} evidence values for cell {}, the session's others {}", labels.utime,
                                     e.values.size(), i, info.evidence_size));
    if (stereo::to_state(e.verdict) != labels.stereo_state[i]) {
      ++report.evidence_mismatches;
      std::fill(e.values.begin(), e.values.end(), std::numeric_limits<float>::quiet_NaN());
      if (!evidence_warned)
        spdlog::warn(
            "frame {} cell {}: {} re-run says {}, the labels' verdict is state {}: evidence stored as NaN "
            "where they differ (recorded with other detector settings? re-label with --labels {} and those "
            "settings)",
            labels.utime, i, labels.detector, stereo::to_string(e.verdict), static_cast<int>(labels.stereo_state[i]),
            labels.detector);
      evidence_warned = true;
    }
    out[i] = std::move(e.values);
  }
  return out;
}

SessionBuilder::SessionBuilder(const std::string& dataset_root, const std::string& session, BuildOptions options)
    : impl_(std::make_unique<Impl>()) {
  check_session_name(session);  // before a log is read, not at its first sample
  impl_->root = dataset_root;
  impl_->session = session;
  impl_->options = std::move(options);
  if (impl_->rerun()) {
    const auto names = stereo::detector_names();
    if (std::find(names.begin(), names.end(), impl_->options.labels) == names.end())
      throw std::invalid_argument("labels '" + impl_->options.labels + "': use 'recorded' or a detector name");
    impl_->info.detector = impl_->options.labels;
    impl_->info.grid = impl_->options.grid;
    impl_->info.patch_size = impl_->options.grid.patch_size;
  }
  if (impl_->options.recorded_patch_size < 0 || (impl_->rerun() && impl_->options.recorded_patch_size > 0))
    throw std::invalid_argument(
        "recorded_patch_size must be > 0 and is for recorded labels (re-run labels cut "
        "grid.patch_size)");
  if (!(impl_->options.patch_scale >= 0))
    throw std::invalid_argument("patch_scale must be >= 0 (0: fixed patches), not " +
                                std::to_string(impl_->options.patch_scale));
  if (!(impl_->options.keep_tn > 0 && impl_->options.keep_tn <= 1))
    throw std::invalid_argument("keep_tn must be in (0, 1], not " + std::to_string(impl_->options.keep_tn));
  if (impl_->options.views != 1 && impl_->options.views != 2)
    throw std::invalid_argument("views must be 1 or 2, not " + std::to_string(impl_->options.views));
  list_sessions(dataset_root);  // a damaged index is found now, not once the session is built
  impl_->info.session = session;
  impl_->info.labels_from = impl_->rerun() ? "rerun" : "recorded";
}

std::string pairing_warning(const BuildReport& r, const monitor::PairingConfig& pairing) {
  // Not against frames_labelled: a paired frame may give no sample (every cell unknown, or stored already).
  if (r.frames_unmatched < 5 || 2 * r.frames_unmatched <= r.stereo_frames) return "";
  return fmt::format(
      "{} of its {} stereo frames have no depth frame within {:.1f} ms (--sync-tolerance-us): a depth camera slower "
      "than the stereo one, or on another clock? Half the depth frame period pairs them",
      r.frames_unmatched, r.stereo_frames, static_cast<double>(pairing.tolerance_us) / 1e3);
}

// Destroyed before finish() (a log that could not be read, an error part-way):
// what was written stays unregistered.
SessionBuilder::~SessionBuilder() {
  if (impl_->writer) impl_->writer->abandon();
}

void SessionBuilder::add_log(const std::string& path, const ProgressCallback& progress) {
  Impl& m = *impl_;
  const std::string source = std::filesystem::absolute(path).lexically_normal().string();  // found from any folder
  m.info.logs.push_back(source);
  if (m.writer) m.writer->add_source_log(source);  // opened with the logs read before this one
  // Damage is skipped to the next good event (reported in problems): what follows it is still the session's.
  logio::LogReader reader(path, {/*resync=*/true});  // throws LogReadError for a missing file
  logio::LogEvent e;
  const auto& o = m.options;
  while (reader.next(e)) {
    ++m.report.events;
    if (e.channel == o.calibration_channel) m.on_calibration(e);
    else if (!m.rig) continue;  // nothing is usable before the calibration
    else if (e.channel == o.stereo_channel) m.on_stereo(e);
    else if (e.channel == o.depth_channel) m.on_depth(e);
    else if (e.channel == o.labels_channel) m.on_labels(e);
    else if (e.channel == o.truth_channel) m.on_truth(e);
    // other channels: ignored
    if (progress && (m.report.events & 15) == 0) progress(reader.position(), reader.size());
  }
  if (progress) progress(reader.position(), reader.size());
  for (const auto& p : reader.problems()) m.report.problems.push_back(path + ": " + p.describe());
  if (m.rig) return;
  if (const std::string why = reader.not_a_log(); !why.empty()) throw DatasetError(path + ": " + why);
  throw DatasetError(path + ": no " + o.calibration_channel +
                     " message in the log; a log must hold the rig calibration (record it with ivoa-logger; one "
                     "recorded under another name is read with --calibration-channel)");
}

BuildReport SessionBuilder::finish() {
  Impl& m = *impl_;
  if (m.label_sources == 0 || m.report.stereo_frames == 0) throw DatasetError(m.no_label_source());
  if (m.pipeline) m.take(m.pipeline->flush());
  m.emit_ready(true);
  if (m.report.samples == 0 && (m.report.frames_unmatched == m.report.stereo_frames || m.replaces_samples()))
    throw DatasetError(m.no_samples());
  if (!m.writer && !m.frames_by_size.empty()) m.set_image_size(m.frames_by_size.front().first);
  m.open_writer();  // a session without samples (no cell the detector judged) is still written, so it is listed
  m.count_frames_of_other_sizes();
  m.writer->close();
  return m.report;
}

}  // namespace ivoa::dataset
