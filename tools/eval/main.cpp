// ivoa-eval: a model's MC-dropout predictions and FC2 embeddings on dataset
// sessions, and per-frame overlay figures from logs (see README.md).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/image_files.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/progress.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/figures/paper_figure.hpp"
#include "ivoa/introspection/model.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/session_name.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"
#include "overlay.hpp"

namespace fs = std::filesystem;
using namespace ivoa;

namespace {

// Thrown between batches or logs once a signal asks the run to stop:
// unwinding removes the .partial files. `kept`: what the output folder holds.
struct Stopped {
  const char* kept;
};
constexpr const char* kKeptEarlier = "an earlier run's outputs, if any, as they were";
constexpr const char* kKeptPredictions = "this run's predictions and embeddings, not all of its overlays";

struct Options {
  std::string model, dataset, split_file, out;
  std::vector<std::string> splits{"test"};
  std::vector<std::string> logs;
  int overlay_every = 10;
  int max_overlays = 12;
  double overlay_scale = 0.6;
  double uncertainty_max = -1;      // < 0: the largest of the run's overlays; 0: each frame's own
  bool dots_given_verdict = false;  // overlay dots: predictions given the recorded verdict
  introspection::InferenceConfig inference;
  // The --logs' channels read for overlays (defaults: the processes' own).
  std::string stereo_channel{channels::kStereoImages};
  std::string calibration_channel{channels::kRigCalibration};
  std::string truth_channel{channels::kSimGroundTruth};
};

constexpr const char* kHeader =
    "session,environment,split,sample,utime,cell,x,y,u,v,label,predicted,p_tp,p_tn,p_fp,p_fn,var_predicted,"
    "uncertainty,var_tp,var_tn,var_fp,var_fn,phenomena,phenomenon,surface,stereo_state,verdict_predicted,p_wrong,"
    "var_wrong";

// A file under --out that cannot be written (exit code: I/O error, not bad input).
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Refuses a session whose patches the model was not trained on; warns
// where thinned TN cells bias the overall figures.
// Both mismatches are named at once, so one rebuild fixes them.
void check_session_fits(const dataset::SessionInfo& info, const introspection::ModelInfo& model) {
  std::string differs, flags;
  if (info.patch_scale != model.patch_scale) {
    differs = fmt::format("patch scale {} (model: {})", info.patch_scale, model.patch_scale);
    flags = fmt::format("--patch-scale {}", model.patch_scale);
  }
  if (info.views != model.views) {
    differs += fmt::format("{}{} view(s) per patch (model: {})", differs.empty() ? "" : ", ", info.views, model.views);
    flags += fmt::format("{}--views {}", flags.empty() ? "" : " ", model.views);
  }
  if (info.patch_size != model.patch_size) {  // its patches would be resized to the model's, unlike in training
    differs +=
        fmt::format("{}{} px patches (model: {})", differs.empty() ? "" : ", ", info.patch_size, model.patch_size);
    flags += fmt::format("{}--patch-size {}", flags.empty() ? "" : " ", model.patch_size);
  }
  if (!differs.empty())
    throw dataset::DatasetError(
        fmt::format("session {} has {}: model {} was not trained on such patches (build the "
                    "dataset with {})",
                    info.session, differs, model.id, flags));
  if (info.tn_kept < 1)
    spdlog::warn(
        "session {} stores {:.0f} % of its TN cells (ivoa-dataset --keep-tn): its per-class accuracies stand, "
        "but overall accuracy and failure precision count too few TN; rebuild it with every TN to report those",
        info.session, 100 * info.tn_kept);
}

// One predictions.csv row (kHeader's columns).
void write_row(std::FILE* csv, const dataset::SessionInfo& info, const std::string& split, size_t index,
               const dataset::SampleRecord& s, const introspection::Prediction& p,
               const introspection::VerdictPrediction& v) {
  std::fprintf(
      csv,
      "%s,%s,%s,%zu,%lld,%d,%.3f,%.3f,%.1f,%.1f,%d,%d,%.5f,%.5f,%.5f,%.5f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,"
      "%d,%d,%.5f,%.6g\n",
      info.session.c_str(), info.environment.c_str(), split.c_str(), index, static_cast<long long>(s.utime), s.cell,
      s.x, s.y, s.u, s.v, s.label, p.predicted, p.probability[0], p.probability[1], p.probability[2], p.probability[3],
      p.variance, p.uncertainty, p.class_variance[0], p.class_variance[1], p.class_variance[2], p.class_variance[3],
      s.phenomena, s.phenomenon, s.surface, s.stereo_state, v.predicted, v.p_wrong, v.variance);
}

// Every sample of the session through the model, in batches: a row each in
// the CSV and its FC2 embedding in the embeddings file.
void write_rows(std::FILE* csv, std::FILE* emb, const dataset::SessionReader& session, const std::string& split,
                introspection::IntrospectionModel& model, Progress& progress, double& done) {
  constexpr size_t kBatch = 256;
  const auto& info = session.info();
  check_session_fits(info, model.info());
  for (size_t begin = 0; begin < session.size(); begin += kBatch) {
    if (stop_requested()) throw Stopped{kKeptEarlier};
    const size_t end = std::min(session.size(), begin + kBatch);
    session.prefetch(begin, 2 * kBatch);  // this batch and, while it runs, the next
    std::vector<cv::Mat> patches;
    for (size_t i = begin; i < end; ++i) patches.push_back(session.patch(i));
    const introspection::PatchOutputs out = model.run_patches(patches, true);
    for (size_t i = begin; i < end; ++i) {
      const auto& s = session.samples()[i];
      const auto& p = out.predictions[i - begin];
      if (!std::all_of(p.probability.begin(), p.probability.end(), [](float v) { return std::isfinite(v); }))
        throw introspection::ModelError(
            fmt::format("{}: predicts a probability that is not a number (session {}, sample {}): its weights "
                        "overflow on real input (a training that diverged?)",
                        model.info().id, info.session, i));
      // Given the verdict the detector recorded for this cell, as the live process sees it.
      const auto v =
          introspection::given_verdict(p, s.stereo_state == obstacle_grid_t::STATE_OBSTACLE, model.verdict_threshold());
      write_row(csv, info, split, i, s, p, v);
      const auto& e = out.embeddings[i - begin];
      std::fwrite(e.data(), sizeof(float), e.size(), emb);
    }
    done += static_cast<double>(end - begin);
    progress.update(done);
  }
}

// The prediction for each labelled cell, as ivoa-introspection makes it
// (a footprint-scaled model's near cells from the squares the dataset
// recorded); given_verdict: conditioned on the cell's recorded verdict where
// it has one, as the live process does with the detector's grid.
void predict_cells(introspection::IntrospectionModel& model, const introspection::Heatmaps& h, const cv::Mat& input,
                   std::vector<tools::LabelledCell>& cells, bool given_verdict) {
  const bool scaled = model.info().patch_scale > 0;
  std::vector<introspection::IntrospectionModel::CellPatch> squares;
  for (const auto& c : cells) squares.push_back({c.u, c.v, scaled ? c.patch_side : model.info().patch_size});
  const auto predictions = model.predict_query_cells(input, h, squares);
  tools::set_predictions(cells, predictions, given_verdict, model.verdict_threshold());
}

using LabelledFrames = std::map<int64_t, std::vector<tools::LabelledCell>>;  // by stereo utime

LabelledFrames labelled_frames(const dataset::SessionReader& reader) {
  LabelledFrames frames;
  for (const auto& s : reader.samples())
    frames[s.utime].push_back({s.u, s.v, s.label, -1, true, s.patch_side, s.stereo_state});
  return frames;
}

// One frame for an overlay figure: the model run on it and on its labelled
// cells. Drawn once every figure's heatmaps are known (their shared scale);
// the left image stays as the log has it until then.
struct PendingOverlay {
  std::string path;
  image_t left;
  introspection::Heatmaps heatmaps;
  std::vector<tools::LabelledCell> cells;
};

PendingOverlay prepare_overlay(const Options& o, introspection::IntrospectionModel& model, const stereo_image_t& msg,
                               const GroundWarp* warp, std::vector<tools::LabelledCell> cells, std::string path) {
  const cv::Mat left = decode_image(msg.left);
  const cv::Mat input = warp ? warp->stack(left, decode_image(msg.right)) : left;
  introspection::Heatmaps h = model.run(input);
  predict_cells(model, h, input, cells, o.dots_given_verdict);
  return {std::move(path), msg.left, std::move(h), std::move(cells)};
}

void write_overlay(const Options& o, const PendingOverlay& p, double uncertainty_max) {
  cv::Mat figure =
      tools::compose_frame_figure(decode_image(p.left), p.heatmaps, p.cells, o.dots_given_verdict, uncertainty_max);
  cv::resize(figure, figure, cv::Size(), o.overlay_scale, o.overlay_scale, cv::INTER_AREA);
  if (std::string error; !write_image_file(p.path, figure, error)) throw OutputError(error);
}

using SessionList = std::vector<std::pair<std::string, std::string>>;  // (split, session)

// Why a simulated log is not of the session's scene and seed ("" if it is,
// or says nothing): every seed-31 session shares its frame times, so a log
// given under another session's name would have that session's labels
// drawn on its images.
std::string other_scene(const logio::LogEvent& e, const dataset::SessionInfo& session) {
  sim_ground_truth_t truth;
  if (session.scene.empty() || !logio::decode(e, truth)) return "";
  if (truth.scene == session.scene && (session.seed < 0 || truth.seed == session.seed)) return "";
  return fmt::format("a log of scene {} seed {}, but session '{}' was recorded from scene {} seed {}", truth.scene,
                     truth.seed, session.session, session.scene, session.seed);
}

// At most `room` overlays of one session's log, every overlay_every-th
// labelled frame; none if a simulated log turns out to be of another scene.
// `labelled_seen` counts the session's labelled frames on from its earlier
// split parts, so the spacing runs across them.
std::vector<PendingOverlay> prepare_log_overlays(const Options& o, introspection::IntrospectionModel& model,
                                                 const std::string& log, const dataset::SessionReader& session,
                                                 size_t room, int64_t& labelled_seen) {
  const LabelledFrames frames = labelled_frames(session);
  logio::LogReader in(log, {/*resync=*/true});
  logio::LogEvent e;
  // The simulator publishes a frame's truth after its images: read on past
  // a full budget until the truth has been checked.
  bool scene_checked = session.info().scene.empty();
  std::vector<PendingOverlay> from_log;
  std::unique_ptr<GroundWarp> warp;             // two-view models, from the log's calibration
  int64_t undecodable = 0, session_frames = 0;  // stereo events; of the decoded, the session's labelled frames
  while ((from_log.size() < room || !scene_checked) && in.next(e)) {
    if (stop_requested()) throw Stopped{kKeptPredictions};  // a long log is minutes of reading
    if (!scene_checked && e.channel == o.truth_channel) {
      scene_checked = true;
      if (const std::string why = other_scene(e, session.info()); !why.empty()) {
        spdlog::warn("{}: {}: no overlays from it", log, why);
        return {};
      }
    }
    if (model.info().views == 2 && !warp && e.channel == o.calibration_channel) {
      rig_calibration_t rig;
      if (logio::decode(e, rig)) warp = std::make_unique<GroundWarp>(from_message(rig));
      continue;
    }
    stereo_image_t msg;
    if (from_log.size() >= room || e.channel != o.stereo_channel) continue;
    if (!logio::decode(e, msg)) {
      ++undecodable;
      continue;
    }
    const auto it = frames.find(msg.utime);
    if (it == frames.end()) continue;
    ++session_frames;
    if (labelled_seen++ % o.overlay_every != 0) continue;
    if (model.info().views == 2 && !warp)
      throw dataset::DatasetError(log + ": no rig calibration before the first frame (a two-view model needs it)");
    const std::string path =
        o.out + "/overlays/" + logio::session_name_of(log) + "_" + std::to_string(msg.utime) + ".png";
    from_log.push_back(prepare_overlay(o, model, msg, warp.get(), it->second, path));
  }
  if (undecodable > 0)
    spdlog::warn("{}: {} {} messages do not decode as stereo pairs: no overlays from them", log, undecodable,
                 o.stereo_channel);
  if (session_frames == 0 && room > 0 && in.not_a_log().empty())
    spdlog::warn("{}: none of session {}'s labelled frames is in it ({} messages by utime): no overlays from it", log,
                 session.info().session, o.stereo_channel);
  if (const std::string why = in.not_a_log(); !why.empty()) spdlog::warn("{}: {}: no overlays from it", log, why);
  else
    for (const auto& p : in.problems())  // cut short or damaged: the frames there have no overlays
      spdlog::warn("{}: {}: no overlays from what was not read", log, p.describe());
  return from_log;
}

// Writes the overlays of --logs. With a fixed --uncertainty-max each log's
// are written as they come; otherwise all are held (the logged left image,
// the heatmaps, the cells: about 2 MB a 960x600 frame) until the shared
// scale is known.
int write_overlays(const Options& o, introspection::IntrospectionModel& model, const SessionList& evaluated) {
  std::error_code error;
  fs::create_directories(o.out + "/overlays", error);
  if (error) throw OutputError(o.out + "/overlays: cannot create the folder: " + error.message());
  const bool fixed_scale = o.uncertainty_max >= 0;
  std::vector<PendingOverlay> held;
  size_t written = 0;
  std::map<std::string, int64_t> labelled_seen;  // by session, over its split parts
  for (const auto& log : o.logs) {
    if (stop_requested()) throw Stopped{kKeptPredictions};
    const std::string session = logio::session_name_of(log);
    const std::string dir = o.dataset + "/" + session;
    if (!fs::exists(dir + "/session.json")) {
      spdlog::warn("{}: no session '{}' in {}: no labels for its overlays, skipped", log, session, o.dataset);
      continue;
    }
    if (std::none_of(evaluated.begin(), evaluated.end(), [&](const auto& s) { return s.second == session; }))
      spdlog::warn("{}: session '{}' is not in the splits evaluated: its overlays are not of the figures' sessions",
                   log, session);
    const size_t room = static_cast<size_t>(o.max_overlays) - std::min<size_t>(o.max_overlays, written + held.size());
    if (room == 0) continue;
    for (auto& p : prepare_log_overlays(o, model, log, dataset::SessionReader(dir), room, labelled_seen[session])) {
      if (!fixed_scale) {
        held.push_back(std::move(p));
        continue;
      }
      write_overlay(o, p, o.uncertainty_max);
      ++written;
    }
  }
  std::vector<cv::Mat> maps;
  for (const auto& p : held) maps.push_back(p.heatmaps.uncertainty);
  const double shared_max = figures::uncertainty_scale_top(maps);
  for (const auto& p : held) {
    if (stop_requested()) throw Stopped{kKeptPredictions};
    write_overlay(o, p, shared_max);
  }
  written += held.size();
  spdlog::info("wrote {} overlay figures to {}/overlays{}", written, o.out,
               written >= static_cast<size_t>(o.max_overlays)
                   ? fmt::format(" (at most --max-overlays {}: give more for more)", o.max_overlays)
                   : "");
  return static_cast<int>(written);
}

// A split named twice is evaluated once (its samples would count twice);
// load_split already refuses a session in two splits.
SessionList list_sessions(const Options& o) {
  SessionList sessions;
  std::set<std::string> listed;
  for (const auto& split : o.splits)
    if (listed.insert(split).second)
      for (const auto& s : dataset::split_sessions(o.split_file, split, o.dataset)) sessions.push_back({split, s});
  if (sessions.empty())
    throw dataset::DatasetError(o.split_file + ": the split(s) " + fmt::format("{}", fmt::join(o.splits, ", ")) +
                                " list no session: nothing to evaluate");
  return sessions;
}

// The sessions to evaluate, read and checked before anything is written.
struct Evaluated {
  std::vector<dataset::SessionInfo> infos;  // in the order of the SessionList
  double samples = 0;
};

Evaluated describe_sessions(const Options& o, const SessionList& sessions, const introspection::ModelInfo& model) {
  Evaluated e;
  std::vector<std::pair<std::string, std::string>> other_detector;  // (session, detector) unlike the model's
  std::vector<std::pair<std::string, cv::Size>> other_size;         // (session, image size) the model has not seen
  for (const auto& [split, name] : sessions) {
    const dataset::SessionReader session(o.dataset + "/" + name);
    e.infos.push_back(session.info());
    e.samples += static_cast<double>(session.size());
    if (session.info().detector != model.detector) other_detector.push_back({name, session.info().detector});
    const cv::Size size = session.info().image_size;
    if (!size.empty() && !introspection::trained_on_size(model, size)) other_size.push_back({name, size});
  }
  if (e.samples == 0)
    throw dataset::DatasetError(fmt::format("{}: the {} session(s) of split(s) {} hold no samples: nothing to evaluate",
                                            o.split_file, sessions.size(), fmt::join(o.splits, ", ")));
  if (!other_detector.empty())
    spdlog::warn(
        "model {} introspects the '{}' detector, but {} of the {} sessions are labelled from another (the first, "
        "{}, from '{}'): their figures say how well it predicts that detector's failures, not its own",
        model.id, model.detector, other_detector.size(), sessions.size(), other_detector.front().first,
        other_detector.front().second);
  if (!other_size.empty())
    spdlog::warn(
        "model {} was trained on {} images, but {} of the {} sessions {} of another size (the first, {}, {}x{}): its "
        "patches are cut on the ground and resized, so it runs, but these figures measure it on a camera it has not "
        "seen (fine-tune it on that camera's sessions: ivoa-train --init {})",
        model.id, introspection::image_sizes_text(model.image_sizes), other_size.size(), sessions.size(),
        other_size.size() == 1 ? "is" : "are", other_size.front().first, other_size.front().second.width,
        other_size.front().second.height, o.model);
  return e;
}

// eval.json, predictions.csv and embeddings.f32 are written beside their
// names and renamed into place once all three are whole: a run that fails
// or is stopped part way leaves an earlier run's outputs as they were (they
// were rewritten in place, a killed run's rows under the earlier eval.json).
class PartialOutputs {
 public:
  explicit PartialOutputs(const std::string& folder) : folder_(folder) {}
  ~PartialOutputs() {
    std::error_code ignored;
    for (const auto& name : names_) fs::remove(partial_path(name), ignored);
  }
  // Where to write `name` until commit().
  std::string partial(const std::string& name) {
    if (std::find(names_.begin(), names_.end(), name) == names_.end()) names_.push_back(name);
    return partial_path(name);
  }
  void commit() {
    for (const auto& name : names_) {
      std::error_code error;
      fs::rename(partial_path(name), folder_ + "/" + name, error);
      if (error) throw OutputError(folder_ + "/" + name + ": cannot write: " + error.message());
    }
    names_.clear();
  }

 private:
  std::string partial_path(const std::string& name) const { return folder_ + "/" + name + ".partial"; }

  std::string folder_;
  std::vector<std::string> names_;
};

// predictions.csv and embeddings.f32 (one FC2 vector per row); returns the
// number of rows.
double write_predictions(const Options& o, const SessionList& sessions, introspection::IntrospectionModel& model,
                         double total, PartialOutputs& outputs) {
  const std::string csv_path = outputs.partial("predictions.csv"), emb_path = outputs.partial("embeddings.f32");
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> csv(std::fopen(csv_path.c_str(), "w"), &std::fclose);
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> emb(std::fopen(emb_path.c_str(), "wb"), &std::fclose);
  if (!csv || !emb)
    throw OutputError((!csv ? csv_path : emb_path) + ": cannot open for writing: " + std::strerror(errno));
  std::fprintf(csv.get(), "%s\n", kHeader);
  Progress progress("evaluating (T = " + std::to_string(o.inference.mc_passes) + ")", total, "samples");
  double done = 0;
  for (const auto& [split, name] : sessions) {
    const dataset::SessionReader session(o.dataset + "/" + name);
    write_rows(csv.get(), emb.get(), session, split, model, progress, done);
  }
  progress.finish();
  // A full disk shows only here: say so rather than leave short files behind unnoticed.
  if (std::fflush(csv.get()) != 0 || std::ferror(csv.get())) throw OutputError(csv_path + ": write failed");
  if (std::fflush(emb.get()) != 0 || std::ferror(emb.get())) throw OutputError(emb_path + ": write failed");
  return done;
}

// The patches each session was cut as, so the report can refuse a dataset
// cut otherwise (its mosaics would show other patches than the model saw).
void write_eval_json(const Options& o, const introspection::IntrospectionModel& model, const SessionList& sessions,
                     const std::vector<dataset::SessionInfo>& infos, double samples, PartialOutputs& outputs) {
  std::string evaluated;
  for (size_t k = 0; k < sessions.size(); ++k)
    evaluated += fmt::format(
        "{}{{\"split\": {}, \"session\": {}, \"patch_scale\": {}, \"views\": {}, \"image_size\": [{}, {}]}}",
        k ? ", " : "", json_quote(sessions[k].first), json_quote(sessions[k].second), infos[k].patch_scale,
        infos[k].views, infos[k].image_size.width, infos[k].image_size.height);
  const auto& info = model.info();
  const std::string path = outputs.partial("eval.json");
  std::ofstream json(path);
  json << "{\"model\": " << json_quote(info.id) << ", \"dataset\": " << json_quote(fs::absolute(o.dataset).string())
       << ", \"mc_passes\": " << o.inference.mc_passes
       << ", \"uncertainty_threshold\": " << model.uncertainty_threshold()
       << ", \"verdict_uncertainty_threshold\": " << model.verdict_threshold() << ", \"overlay_dots\": \""
       << (o.dots_given_verdict ? "given_verdict" : "image") << "\", \"samples\": " << samples << ", \"sessions\": ["
       << evaluated << "], \"metadata\": {\"detector\": " << json_quote(info.detector)
       << ", \"architecture\": " << json_quote(info.architecture)
       << ", \"image_sizes\": " << introspection::image_sizes_json(info.image_sizes)
       << ", \"training\": " << (info.training_summary.empty() ? "{}" : info.training_summary) << "}}\n";
  if (!json.flush()) throw OutputError(path + ": cannot write: " + std::strerror(errno));
}

void add_options(CLI::App& app, Options& o) {
  app.add_option("--model", o.model, "model file")->required()->check(ivoa::input_file());
  app.add_option("--dataset", o.dataset, "dataset folder")->required()->check(ivoa::input_folder());
  app.add_option("--split", o.split_file, "split file")->required()->check(ivoa::input_file());
  app.add_option("--splits", o.splits, "splits to evaluate")->delimiter(',')->capture_default_str();
  app.add_option("--out", o.out, "output folder")->required();
  app.add_option("--logs", o.logs, "logs of evaluated sessions, for overlay figures")->check(ivoa::input_file());
  app.add_option("--overlay-every", o.overlay_every, "one overlay per this many labelled frames")
      ->capture_default_str()
      ->check(positive_number());
  app.add_option("--max-overlays", o.max_overlays, "at most this many overlay figures in all")
      ->capture_default_str()
      ->check(non_negative_number());
  app.add_option("--uncertainty-max", o.uncertainty_max,
                 "top of the overlays' uncertainty colour scale, class variance (default: the largest value over "
                 "the run's overlays, one scale for all; 0: each frame its own maximum, as the paper's figures)")
      ->check(non_negative_number());
  app.add_flag("--dots-given-verdict", o.dots_given_verdict,
               "overlay dots: predictions given the detector's recorded verdict (default: from the image alone, as the "
               "paper)");
  add_log_channel_option(app, "--stereo-channel", o.stereo_channel, "stereo pairs (overlays of --logs)");
  add_log_channel_option(app, "--calibration-channel", o.calibration_channel,
                         "the rig calibration (overlays of --logs, two-view models)");
  add_log_channel_option(app, "--truth-channel", o.truth_channel,
                         "the simulator's ground truth (checks that a --logs file is the session's scene)");
  app.add_option("--mc-passes", o.inference.mc_passes, "Monte-Carlo dropout passes per sample (the paper's T)")
      ->capture_default_str()
      ->check(number_in(1, 1000));  // as ivoa-introspection: 1e6 passes grew past 10 GB
  app.add_option("--threads", o.inference.threads, "LibTorch threads")->capture_default_str()->check(number_in(1, 256));
  app.add_option("--seed", o.inference.seed, "dropout masks (0: from the clock, a new draw each run)")
      ->capture_default_str()
      ->check(ivoa::seed_number());
}

// The dataset, or the folder in it that links to a session folder elsewhere,
// that `out` lies in; "" if none.
std::string dataset_folder_holding(const std::string& out, const std::string& dataset) {
  if (lies_within(out, dataset)) return dataset;
  std::error_code error, broken_link;
  for (fs::directory_iterator it(dataset, error), end; !error && it != end; it.increment(error))
    if (it->is_symlink(broken_link) && it->is_directory(broken_link) && lies_within(out, it->path().string()))
      return it->path().string();
  return "";
}

// The figures of an earlier run into the same --out would pass for this
// model's (the report shows every overlay it finds there): those named as
// prepare_log_overlays names them, <session>_<utime>.png, are removed.
void remove_old_overlays(const std::string& folder) {
  static const std::regex kOverlayName(R"(.+_[0-9]{10,}\.png)");
  std::error_code error;
  int removed = 0;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (!entry.is_regular_file() || !std::regex_match(entry.path().filename().string(), kOverlayName)) continue;
    if (fs::remove(entry.path(), error)) ++removed;
    else spdlog::warn("{}: cannot remove this overlay of an earlier run: {}", entry.path().string(), error.message());
  }
  if (removed > 0) spdlog::info("removed {} overlay figures of an earlier run from {}", removed, folder);
}

// Evaluated sessions the model was trained or validated on (its training
// summary names them; the report warns of them too): not held out.
void warn_of_sessions_seen_in_training(const SessionList& sessions, const std::string& training_summary) {
  YAML::Node training;
  try {
    training = YAML::Load(training_summary);  // JSON, which YAML reads
  } catch (const YAML::Exception&) {
    return;  // an older or foreign model: nothing to compare
  }
  for (const auto& [key, how] :
       {std::pair{"train_sessions", "trained on"}, std::pair{"val_sessions", "validated on"}}) {
    if (!training.IsMap() || !training[key].IsSequence()) continue;
    std::set<std::string> used;
    for (const auto& name : training[key]) used.insert(name.as<std::string>(""));
    std::vector<std::string> seen;
    for (const auto& [split, session] : sessions)
      if (used.count(session)) seen.push_back(session);
    if (!seen.empty())
      spdlog::warn("the model was {} {} of the {} sessions evaluated ({}): their figures are not held out", how,
                   seen.size(), sessions.size(), fmt::join(seen, ", "));
  }
}

int evaluate(const Options& o) {
  auto model = introspection::IntrospectionModel::load(o.model, o.inference);
  const SessionList sessions = list_sessions(o);
  warn_of_sessions_seen_in_training(sessions, model->info().training_summary);
  const Evaluated evaluated = describe_sessions(o, sessions, model->info());
  std::error_code error;
  fs::create_directories(o.out, error);
  if (error) throw OutputError(o.out + ": cannot create the output folder: " + error.message());
  PartialOutputs outputs(o.out);
  const double samples = write_predictions(o, sessions, *model, evaluated.samples, outputs);
  write_eval_json(o, *model, sessions, evaluated.infos, samples, outputs);
  outputs.commit();
  remove_old_overlays(o.out + "/overlays");
  if (!o.logs.empty()) write_overlays(o, *model, sessions);
  std::printf("predictions: %s/predictions.csv (%.0f samples), embeddings: %s/embeddings.f32\n", o.out.c_str(), samples,
              o.out.c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  introspection::tune_libtorch_runtime(argv);
  CLI::App app{"Run a model on dataset sessions: predictions, uncertainties, embeddings, overlay figures"};
  CommonOptions common;
  add_offline_options(app, common);
  Options o;
  o.inference.seed = 1;
  add_options(app, o);
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  init_logging("eval", common.log_level);
  if (const std::string twice = file_given_twice(o.logs); !twice.empty()) {
    spdlog::error("--logs {} is given twice: its overlays would be drawn twice", twice);
    return kExitUsage;
  }
  while (o.out.size() > 1 && o.out.back() == '/') o.out.pop_back();  // "eval/" prints as eval/x, not eval//x
  if (o.inference.mc_passes == 1)
    spdlog::warn(
        "--mc-passes 1: one pass without dropout, so every variance is 0 and the uncertainty gates keep "
        "everything (the report's sweep says 'not measured'; the paper's T is 20)");
  if (const std::string folder = dataset_folder_holding(o.out, o.dataset); !folder.empty()) {
    spdlog::error(
        "--out {} lies in the dataset {}{}: an evaluation's files there would mix with its sessions (a session "
        "folder holding them can no longer be rebuilt); give a folder outside it",
        o.out, o.dataset, folder == o.dataset ? "" : fmt::format(" (in {}, a link to a session folder)", folder));
    return kExitUsage;
  }
  install_stop_handlers();
  try {
    return evaluate(o);
  } catch (const Stopped& stopped) {
    const int sig = stop_signal();
    spdlog::warn("stopped by signal {}: {} holds {}", sig, o.out, stopped.kept);
    std::signal(sig, SIG_DFL);  // exit as the signal would have, for the shell and the launcher
    std::raise(sig);
    return kExitFailure;
  } catch (const OutputError& e) {
    spdlog::error("{}", e.what());
    return kExitIoError;
  } catch (const std::exception& e) {  // the model, split or dataset: the message names which and where
    spdlog::error("{}", e.what());
    return kExitBadInput;
  }
}
