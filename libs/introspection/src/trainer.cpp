#include "ivoa/introspection/training.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <ATen/CPUGeneratorImpl.h>
#include <spdlog/spdlog.h>
#include <torch/torch.h>
#include <yaml-cpp/yaml.h>

#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/label_confusion.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "augmentation.hpp"
#include "evidence_task.hpp"
#include "mc_dropout.hpp"
#include "model_file.hpp"
#include "tensors.hpp"

namespace ivoa::introspection {
namespace {

struct SampleRef {
  uint32_t session;
  uint32_t index;
};

// The samples of one split, grouped by class, patches memory-mapped.
struct SplitData {
  std::vector<std::unique_ptr<dataset::SessionReader>> sessions;
  std::array<std::vector<SampleRef>, kNumClasses> by_class;
  std::vector<std::string> names;
  int patch_size = 0;
  int views = 0;
  double patch_scale = -1;     // -1 until the first session is read
  int evidence_size = -1;      // values per sample; 0 if a session has none
  bool some_evidence = false;  // a session carries evidence (0 above then means they disagree)
  std::string detector;        // whose failures the labels are: one for all

  size_t size() const {
    size_t n = 0;
    for (const auto& c : by_class) n += c.size();
    return n;
  }
};

// A model trained partly on sessions of unknown size cannot say which sizes
// it knows: none are recorded then (and the user is told), rather than a
// list that would call a size it was trained on unknown.
std::vector<cv::Size> distinct_image_sizes(const std::vector<std::unique_ptr<dataset::SessionReader>>& sessions) {
  std::vector<cv::Size> sizes;
  for (const auto& session : sessions) {
    if (session->size() == 0) continue;  // nothing of it is learnt
    const cv::Size size = session->info().image_size;
    if (size.empty()) {
      spdlog::warn(
          "session {} was built before sessions recorded their image size: the model will record none, so no tool "
          "can say when it meets a camera it was not trained on (rebuild the session with ivoa-dataset build)",
          session->info().session);
      return {};
    }
    if (std::find(sizes.begin(), sizes.end(), size) == sizes.end()) sizes.push_back(size);
  }
  return sizes;
}

SplitData load_split_data(const TrainConfig& c, const std::string& split) {
  const std::vector<std::string> names = dataset::split_sessions(c.split_file, split, c.dataset);
  if (names.empty()) throw std::runtime_error(c.split_file + ": no sessions in split '" + split + "'");
  SplitData d;
  for (const auto& name : names) {
    auto reader = std::make_unique<dataset::SessionReader>(c.dataset + "/" + name);
    if (d.patch_size == 0) d.patch_size = reader->info().patch_size;
    if (reader->info().patch_size != d.patch_size)
      throw std::runtime_error(name + ": patch size differs from the other sessions");
    if (d.views == 0) d.views = reader->info().views;
    if (reader->info().views != d.views)
      throw std::runtime_error(name + ": " + std::to_string(reader->info().views) + " view(s), the other sessions " +
                               std::to_string(d.views));
    if (d.sessions.empty()) d.detector = reader->info().detector;
    if (reader->info().detector != d.detector)
      throw std::runtime_error(fmt::format(
          "{}: labelled from the '{}' detector, the other sessions from '{}' (a model introspects one detector)", name,
          reader->info().detector, d.detector));
    if (d.patch_scale < 0) d.patch_scale = reader->info().patch_scale;
    if (reader->info().patch_scale != d.patch_scale)
      throw std::runtime_error(
          fmt::format("{}: patch scale {}, the other sessions {}", name, reader->info().patch_scale, d.patch_scale));
    const int evidence_size = reader->info().evidence_size;  // sessions that disagree cannot share the side task
    d.evidence_size = d.evidence_size < 0 || d.evidence_size == evidence_size ? evidence_size : 0;
    d.some_evidence = d.some_evidence || evidence_size > 0;
    const auto session = static_cast<uint32_t>(d.sessions.size());
    for (size_t i = 0; i < reader->size(); ++i)
      d.by_class[static_cast<size_t>(reader->samples()[i].label)].push_back({session, static_cast<uint32_t>(i)});
    d.names.push_back(name);
    d.sessions.push_back(std::move(reader));
  }
  return d;
}

// Where each sample's raw patch lies (memory-mapped), with the reads of
// the ones not yet in memory started together rather than one by one.
std::vector<const uint8_t*> patch_pointers(const SplitData& d, const std::vector<SampleRef>& refs) {
  for (const auto& r : refs) d.sessions[r.session]->prefetch(r.index);
  std::vector<const uint8_t*> out;
  out.reserve(refs.size());
  for (const auto& r : refs) out.push_back(d.sessions[r.session]->patch_data(r.index));
  return out;
}

// The batch's evidence targets [B, size] (NaN: not measured).
torch::Tensor evidence_targets(const SplitData& d, const std::vector<SampleRef>& refs, int size) {
  std::vector<float> values;
  values.reserve(refs.size() * static_cast<size_t>(size));
  for (const auto& r : refs) {
    const float* e = d.sessions[r.session]->evidence(r.index);
    values.insert(values.end(), e, e + size);
  }
  return torch::from_blob(values.data(), {static_cast<int64_t>(refs.size()), size}, torch::kFloat).clone();
}

const dataset::SampleRecord& sample_of(const SplitData& d, const SampleRef& r) {
  return d.sessions[r.session]->samples()[r.index];
}
int label_of(const SplitData& d, const SampleRef& r) { return sample_of(d, r).label; }

std::string json_list(const std::vector<std::string>& v) {
  std::string s = "[";
  for (size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + json_quote(v[k]);
  return s + "]";
}

// A fixed, deterministic validation subset spread over all sessions and classes.
// Fewer validation samples than this, and which step is kept and where the
// gates fall are mostly chance (a class then has a few dozen cells or none).
constexpr size_t kFewValidationSamples = 500;

std::vector<SampleRef> validation_subset(const SplitData& d, int64_t max_samples) {
  if (d.size() == 0)
    throw std::runtime_error("the validation sessions (" + json_list(d.names) +
                             ") have no labelled samples: nothing to validate or calibrate on");
  std::vector<SampleRef> all;
  for (const auto& c : d.by_class) all.insert(all.end(), c.begin(), c.end());
  std::vector<SampleRef> out;
  const bool capped = static_cast<int64_t>(all.size()) > max_samples;
  if (!capped) {
    out = std::move(all);
  } else {
    const double step = static_cast<double>(all.size()) / static_cast<double>(max_samples);
    for (int64_t k = 0; k < max_samples; ++k) out.push_back(all[static_cast<size_t>(static_cast<double>(k) * step)]);
  }
  if (out.size() < kFewValidationSamples)
    spdlog::warn(
        "validating on {} samples: the best step and the uncertainty gates rest on them and are largely chance "
        "({})",
        out.size(), capped ? "a larger --max-val-samples makes them more" : "more validation sessions make them more");
  return out;
}

struct ValOutputs {
  LabelConfusion confusion;
  bool outputs_finite = true;  // false: the class probabilities overflowed
  std::vector<int> truth, predicted;
  std::vector<float> variance;  // predicted-class variance (MC only)
  // given_verdict() of the detector's verdict the sample recorded (stereo_state).
  std::vector<int> verdict_predicted;
  std::vector<float> verdict_variance;
};

// Validation runs in batches; the cells of a batch share their MC-dropout
// masks, as the cells of a live frame do.
constexpr size_t kValBatch = 256;

ValOutputs run_validation(IntrospectionNetImpl& net, const SplitData& d, const std::vector<SampleRef>& refs,
                          const ModelInfo& info, torch::Device device, int passes, torch::Generator& g) {
  BatchAugmenter decode(info, false, 0);  // normalisation only
  torch::NoGradGuard no_grad;
  net.eval();
  ValOutputs out;
  for (size_t begin = 0; begin < refs.size(); begin += kValBatch) {
    const std::vector<SampleRef> batch(refs.begin() + static_cast<long>(begin),
                                       refs.begin() + static_cast<long>(std::min(refs.size(), begin + kValBatch)));
    const auto features = net.features(decode(patch_pointers(d, batch)).to(device));
    const McStats s = passes > 1 ? mc_dropout_head(net, features, passes, g) : deterministic_head(net, features);
    out.outputs_finite = out.outputs_finite && torch::isfinite(s.mean).all().item<bool>();
    const auto predicted = s.mean.argmax(1).to(torch::kCPU);
    const auto variance = s.variance.gather(1, s.mean.argmax(1, true)).squeeze(1).to(torch::kCPU);
    const auto vmean = s.verdict_mean.to(torch::kCPU), vvar = s.verdict_variance.to(torch::kCPU);
    for (size_t i = 0; i < batch.size(); ++i) {
      const auto row = static_cast<int64_t>(i);
      const int t = label_of(d, batch[i]), p = static_cast<int>(predicted[row].item<int64_t>());
      out.confusion.add(t, p);
      out.truth.push_back(t);
      out.predicted.push_back(p);
      out.variance.push_back(variance[row].item<float>());
      Prediction pred;
      for (int64_t k = 0; k < 2; ++k) {
        pred.verdict_error[static_cast<size_t>(k)] = vmean[row][k].item<float>();
        pred.verdict_error_variance[static_cast<size_t>(k)] = vvar[row][k].item<float>();
      }
      const bool said_obstacle = sample_of(d, batch[i]).stereo_state == obstacle_grid_t::STATE_OBSTACLE;
      const VerdictPrediction v = given_verdict(pred, said_obstacle, 0);
      out.verdict_predicted.push_back(v.predicted);
      out.verdict_variance.push_back(v.variance);
    }
  }
  return out;
}

double learning_rate_at(const TrainConfig& c, int64_t step) {
  if (step < c.warmup_steps)
    return c.learning_rate * static_cast<double>(step + 1) / static_cast<double>(c.warmup_steps);
  const double t =
      static_cast<double>(step - c.warmup_steps) / static_cast<double>(std::max<int64_t>(c.steps - c.warmup_steps, 1));
  return c.learning_rate * (0.01 + 0.99 * 0.5 * (1.0 + std::cos(M_PI * std::min(t, 1.0))));
}

// `step`: the step the weights are from. A file written mid-run cannot say
// how far the run got, so steps_planned and which model it keeps say where
// it was going.
std::string training_summary(const TrainConfig& c, const SplitData& train, const SplitData& val, const TrainReport& r,
                             int64_t step) {
  std::ostringstream o;
  o.precision(5);
  // Absolute, as a dataset session names its logs: the model is read from other folders.
  const auto where = [](const std::string& path) {
    return json_quote(std::filesystem::absolute(path).lexically_normal().string());
  };
  o << "{\"dataset\": " << where(c.dataset) << ", \"split_file\": " << where(c.split_file)
    << ", \"train_sessions\": " << json_list(train.names) << ", \"val_sessions\": " << json_list(val.names)
    << ", \"train_class_counts\": [" << r.train_class_counts[0] << ", " << r.train_class_counts[1] << ", "
    << r.train_class_counts[2] << ", " << r.train_class_counts[3] << "], \"steps\": " << step
    << ", \"steps_planned\": " << c.steps << ", \"kept\": \"" << (c.keep_last ? "last" : "best_validated")
    << "\", \"batch_size\": " << c.batch_size << ", \"optimizer\": \"" << optimizer_name(c.optimizer)
    << "\", \"learning_rate\": " << c.learning_rate << ", \"momentum\": " << c.momentum
    << ", \"weight_decay\": " << c.weight_decay << ", \"seed\": " << c.seed
    << ", \"augment\": " << (c.augment ? "true" : "false") << ", \"augment_noise_max\": " << c.augment_noise_max
    << ", \"fn_weight\": " << c.fn_weight
    << ", \"evidence_weight\": " << (train.evidence_size > 0 ? c.evidence_weight : 0.0)
    << ", \"best_step\": " << r.best_step << ", \"val_mean_class_accuracy\": " << r.best_val_mean_class_accuracy
    << ", \"val_accuracy\": " << r.best_val_accuracy << ", \"val_accuracy_retained\": " << r.val_accuracy_retained
    << ", \"threshold_retain\": " << c.threshold_retain << "}";
  return o.str();
}

// The predicted-class variance below which `retain` of the samples lie, and
// the mean per-class accuracy of those samples.
std::pair<double, double> calibrate_threshold(const std::vector<int>& truth, const std::vector<int>& predicted,
                                              const std::vector<float>& variance, double retain) {
  std::vector<float> sorted = variance;
  std::sort(sorted.begin(), sorted.end());
  if (sorted.empty()) return {0.01, 0};
  const double threshold =
      sorted[std::min(sorted.size() - 1, static_cast<size_t>(retain * static_cast<double>(sorted.size())))];
  LabelConfusion kept;
  for (size_t i = 0; i < truth.size(); ++i)
    if (variance[i] <= threshold) kept.add(truth[i], predicted[i]);
  return {threshold, kept.mean_per_class()};
}

// One pass over a small validation set sees few mask draws (one a batch),
// and its variances, so the gate, follow them: on 300 cells the gates of
// four seeds were up to 4.6x apart. The pass is repeated until this many
// draws are pooled.
constexpr size_t kMinMaskDraws = 64;

void append(ValOutputs& to, const ValOutputs& more) {
  auto add = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  add(to.truth, more.truth), add(to.predicted, more.predicted), add(to.variance, more.variance);
  add(to.verdict_predicted, more.verdict_predicted), add(to.verdict_variance, more.verdict_variance);
  to.outputs_finite = to.outputs_finite && more.outputs_finite;
}

// Both gates (the model's own prediction, and the prediction given the
// detector's verdict) from MC-dropout passes over the validation subset.
void calibrate_gates(NativeModel& model, const SplitData& val, const std::vector<SampleRef>& refs, const TrainConfig& c,
                     torch::Device device, torch::Generator& generator, TrainReport& report) {
  const size_t batches = (refs.size() + kValBatch - 1) / kValBatch;
  const size_t repeats = std::max<size_t>(1, (kMinMaskDraws + batches - 1) / std::max<size_t>(batches, 1));
  ValOutputs mc = run_validation(*model.net, val, refs, model.info, device, c.threshold_passes, generator);
  for (size_t r = 1; r < repeats; ++r)
    append(mc, run_validation(*model.net, val, refs, model.info, device, c.threshold_passes, generator));
  std::tie(report.uncertainty_threshold, report.val_accuracy_retained) =
      calibrate_threshold(mc.truth, mc.predicted, mc.variance, c.threshold_retain);
  std::tie(report.verdict_uncertainty_threshold, report.val_verdict_accuracy_retained) =
      calibrate_threshold(mc.truth, mc.verdict_predicted, mc.verdict_variance, c.threshold_retain);
  model.info.uncertainty_threshold = report.uncertainty_threshold;
  model.info.verdict_uncertainty_threshold = report.verdict_uncertainty_threshold;
}

// A model to resume or fine-tune from must take the patches this dataset
// has; a stale checkpoint (another --views or --patch-scale in the same
// --out) is the usual way to get here, so say how to get out.
void check_can_start_from(const ModelInfo& from, const ModelInfo& wanted, bool resuming, const std::string& output) {
  std::string why;
  if (from.architecture != wanted.architecture)
    why = "architecture " + from.architecture + ", not " + wanted.architecture;
  else if (from.patch_scale != wanted.patch_scale)
    why = fmt::format("patch scale {}, the dataset's {}", from.patch_scale, wanted.patch_scale);
  else if (from.views != wanted.views) why = fmt::format("{} view(s), the dataset's {}", from.views, wanted.views);
  else if (resuming && from.detector != wanted.detector)  // fine-tuning for another detector is allowed
    why = fmt::format("the '{}' detector's labels, the dataset's '{}'", from.detector, wanted.detector);
  if (why.empty()) return;
  const std::string remedy = resuming
                                 ? "delete " + output + ".checkpoint.* to train from scratch, or choose another --out"
                                 : "fine-tune from a model trained on patches cut the same way";
  throw std::runtime_error(
      fmt::format("cannot {} from {}: {} ({})", resuming ? "resume" : "start", from.id, why, remedy));
}

// A resumed run goes on with the recipe and the sessions it was started
// with: a model says it was trained with what the run was given last, so
// other settings would be recorded for steps they did not train (and the
// evaluation's held-out check would follow the new split). --steps may grow.
void check_resumed_recipe(const ModelInfo& from, const TrainConfig& c, const SplitData& train) {
  YAML::Node was;
  try {
    was = YAML::Load(from.training_summary);  // JSON, which YAML reads
  } catch (const YAML::Exception&) {
    return;  // no summary kept yet: nothing to compare
  }
  // Another optimiser is refused by the checkpoint's own check, with its remedy.
  const std::string optimizer = optimizer_name(c.optimizer);
  if (!was.IsMap() || was["optimizer"].as<std::string>(optimizer) != optimizer) return;
  std::vector<std::string> changed;
  const auto number = [&](const char* key, double now) {
    if (was[key] && std::abs(was[key].as<double>(now) - now) > 1e-4 * std::max(1.0, std::abs(now)))
      changed.push_back(fmt::format("{} {} (was {})", key, now, was[key].as<std::string>("")));
  };
  number("batch_size", static_cast<double>(c.batch_size));
  number("learning_rate", c.learning_rate);
  number("momentum", c.momentum);
  number("weight_decay", c.weight_decay);
  number("seed", static_cast<double>(c.seed));
  number("augment_noise_max", c.augment_noise_max);
  number("fn_weight", c.fn_weight);
  if (was["augment"] && was["augment"].as<bool>(c.augment) != c.augment)
    changed.push_back(std::string("augment ") + (c.augment ? "on" : "off"));
  if (was["kept"] && was["kept"].as<std::string>("") != (c.keep_last ? "last" : "best_validated"))
    changed.push_back(c.keep_last ? "--keep-last" : "no --keep-last");
  if (was["train_sessions"] && was["train_sessions"].as<std::vector<std::string>>(train.names) != train.names)
    changed.push_back("the training sessions");
  if (changed.empty()) return;
  throw std::runtime_error(fmt::format(
      "cannot resume {}: it was trained with other settings than these: {} (give the run's own settings, or delete "
      "{}.checkpoint.* to train from scratch)",
      from.id, fmt::join(changed, ", "), c.output));
}

// The side task, if the weight and the training sessions allow it.
std::unique_ptr<EvidenceTask> make_evidence_task(const TrainConfig& c, const SplitData& train,
                                                 IntrospectionNetImpl& net, torch::Device device) {
  if (c.evidence_weight <= 0) return nullptr;
  if (train.evidence_size <= 0 && !train.some_evidence && train.detector != "jppc") {
    // only JPP-C records its window costs: the usual case for the dense detector, nothing to fix
    spdlog::info("the '{}' detector records no evidence: training without the side task", train.detector);
    return nullptr;
  }
  if (train.evidence_size <= 0) {
    spdlog::warn(
        "the training sessions carry no detector evidence (or not all the same): training without the side "
        "task (rebuild them with this ivoa-dataset, or pass --evidence-weight 0 to silence this)");
    return nullptr;
  }
  spdlog::info("side task: regress {} evidence values per sample, weight {}", train.evidence_size, c.evidence_weight);
  return std::make_unique<EvidenceTask>(net.fc1->options.in_features(), train.evidence_size, device);
}

// A checkpoint's optimiser state covers the side task's head iff it was
// trained with it: resuming must use the same setting.
void resume_evidence_task(EvidenceTask* evidence, const std::string& checkpoint, double weight) {
  const bool saved = std::filesystem::exists(checkpoint + ".evidence");
  if (evidence && saved) return evidence->load(checkpoint + ".evidence");
  if (!evidence && !saved) return;
  throw std::runtime_error(
      fmt::format("cannot resume from {}: it was trained {} the evidence side task, this run {} (--evidence-weight {})",
                  checkpoint, saved ? "with" : "without", evidence ? "with" : "without", weight));
}

// What the model file will say about the network, from the training and
// validation sessions (which must have patches cut the same way).
ModelInfo model_info_for(const TrainConfig& c, const SplitData& train, const SplitData& val) {
  if (val.views != train.views)
    throw std::runtime_error("the validation sessions have " + std::to_string(val.views) +
                             " view(s), the training ones " + std::to_string(train.views));
  if (val.patch_scale != train.patch_scale || val.patch_size != train.patch_size)
    throw std::runtime_error(
        fmt::format("the validation sessions' patches (size {}, scale {}) differ from the "
                    "training ones' (size {}, scale {})",
                    val.patch_size, val.patch_scale, train.patch_size, train.patch_scale));
  if (val.detector != train.detector)
    throw std::runtime_error(
        fmt::format("the validation sessions are labelled from the '{}' detector, the training "
                    "ones from '{}'",
                    val.detector, train.detector));
  ModelInfo info;
  info.architecture = c.architecture;
  info.patch_size = train.patch_size;
  info.views = train.views;
  info.patch_scale = train.patch_scale;
  info.image_sizes = distinct_image_sizes(train.sessions);
  info.input_size = input_size_of(c.architecture);
  info.dropout = c.dropout;
  info.detector = train.detector;
  return info;
}

// The classes the training split has (at least two), counted into the report.
std::vector<int> classes_present(const SplitData& train, TrainReport& report) {
  std::vector<int> classes;
  for (int k = 0; k < kNumClasses; ++k) {
    report.train_class_counts[static_cast<size_t>(k)] =
        static_cast<int64_t>(train.by_class[static_cast<size_t>(k)].size());
    if (!train.by_class[static_cast<size_t>(k)].empty()) classes.push_back(k);
    else
      spdlog::warn("training split has no {} samples: the model cannot learn that class",
                   kLabelNames[static_cast<size_t>(k)]);
  }
  if (classes.size() < 2) throw std::runtime_error("training split has fewer than two classes");
  return classes;
}

// Class-balanced sampling with replacement: pick a class, then a sample.
class BalancedSampler {
 public:
  BalancedSampler(const SplitData& train, std::vector<int> classes, double fn_weight, uint64_t seed)
      : train_(train), classes_(std::move(classes)), rng_(seed) {
    std::vector<double> weights;
    for (int k : classes_) weights.push_back(k == 3 ? fn_weight : 1.0);
    pick_class_ = std::discrete_distribution<size_t>(weights.begin(), weights.end());
  }
  std::vector<SampleRef> batch(int size) {
    std::vector<SampleRef> out;
    for (int i = 0; i < size; ++i) {
      const auto& pool = train_.by_class[static_cast<size_t>(classes_[pick_class_(rng_)])];
      out.push_back(pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng_)]);
    }
    return out;
  }

 private:
  const SplitData& train_;
  std::vector<int> classes_;
  std::mt19937_64 rng_;
  std::discrete_distribution<size_t> pick_class_;
};

torch::Tensor labels_of(const SplitData& d, const std::vector<SampleRef>& refs) {
  std::vector<int64_t> labels;
  for (const auto& r : refs) labels.push_back(label_of(d, r));
  return torch::tensor(labels, torch::kLong);
}

// `value` (an optimiser) as torch::save writes it, serialised in memory: the
// file writer finishes in a destructor, where a full disk aborts the process.
template <class Value>
std::string saved_bytes(const Value& value) {
  std::ostringstream out;
  torch::save(value, out);
  return out.str();
}

// An existing --out that is not a model file to replace: a device, folder
// or pipe (as root, /dev/full became a model), the split file, a file of
// the dataset (patches.bin was replaced), or the --init model.
void check_output_is_not_an_input(const TrainConfig& c) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(c.output, error);
  if (!fs::exists(status)) return;
  if (!fs::is_regular_file(status))
    throw std::invalid_argument("--out " + c.output + " exists and is not a file (a device, folder or pipe)");
  if (!same_file_among(c.output, {c.split_file}).empty())
    throw std::invalid_argument("--out " + c.output + " is the split file: it would be written over");
  if (writes_over(c.output, c.dataset))
    throw std::invalid_argument("--out " + c.output + " is a file of the dataset " + c.dataset +
                                ": it would be written over");
  if (writes_over(c.output, c.init))  // the model fine-tuned from would be lost
    throw std::invalid_argument("--out " + c.output + " is the --init model: it would be written over");
}

// The model file's folder, created if need be, before any training.
void make_output_folder(const std::string& output) {
  const std::filesystem::path folder = std::filesystem::path(output).parent_path();
  std::error_code error;
  if (!folder.empty()) std::filesystem::create_directories(folder, error);
  if (error) throw TrainOutputError(output + ": cannot create its folder (" + error.message() + ")");
  // Found now, not after the training: a file can be made beside it (as every save does).
  const std::string probe = output + ".writable";
  errno = 0;
  if (!std::ofstream(probe))
    throw TrainOutputError(output + ": cannot write there (" + std::string(std::strerror(errno)) + ")");
  std::filesystem::remove(probe, error);
}

// Whole or not at all: a write that fails (a full disk) keeps the last model.
void save_model_or_throw(IntrospectionNetImpl& net, const ModelInfo& info, const std::string& path) {
  std::string error;
  if (!replace_file(path, model_bytes(net, info), error)) throw TrainOutputError(error);
}

// A checkpoint: OUT.checkpoint.model, .optimizer, .evidence (side task) and
// .step ("step best_val best_step optimizer"; checkpoints from before AdamW
// have no optimiser name and are SGD's). The four are replaced together, so
// a write that fails part way keeps the last checkpoint whole for --resume.
void save_checkpoint(const std::string& checkpoint, IntrospectionNetImpl& net, const ModelInfo& info,
                     const EvidenceTask* evidence, Optimizer kind, torch::optim::Optimizer& optimizer, int64_t step,
                     const TrainReport& report) {
  std::ostringstream step_line;
  step_line << step << " " << report.best_val_mean_class_accuracy << " " << report.best_step << " "
            << optimizer_name(kind) << "\n";
  FileSet files;
  std::string error;
  const bool staged = files.stage(checkpoint + ".model", model_bytes(net, info), error) &&
                      (!evidence || files.stage(checkpoint + ".evidence", evidence->bytes(), error)) &&
                      files.stage(checkpoint + ".optimizer", saved_bytes(optimizer), error) &&
                      files.stage(checkpoint + ".step", step_line.str(), error);
  if (!staged || !files.commit(error)) throw TrainOutputError(error);
}

// Restores the optimiser and side task of a checkpoint; returns its step.
int64_t load_checkpoint(const std::string& checkpoint, EvidenceTask* evidence, double evidence_weight, Optimizer kind,
                        torch::optim::Optimizer& optimizer, TrainReport& report) {
  int64_t step = 0;
  std::string saved_kind = "sgd";
  std::ifstream step_file(checkpoint + ".step");
  if (!step_file)
    throw std::runtime_error("cannot resume " + checkpoint + ": " + checkpoint + ".step cannot be opened (remove " +
                             checkpoint + ".* to start over)");
  if (!(step_file >> step >> report.best_val_mean_class_accuracy >> report.best_step) || step < 0 ||
      report.best_step < 0 || report.best_step > step)
    throw std::runtime_error("cannot resume " + checkpoint + ": " + checkpoint +
                             ".step is not 'step best_val best_step [optimizer]' (remove " + checkpoint +
                             ".* to start over)");
  step_file >> saved_kind;  // absent before AdamW
  if (saved_kind != optimizer_name(kind))
    throw std::runtime_error("cannot resume " + checkpoint + ": it was trained with --optimizer " + saved_kind +
                             ", this run uses " + optimizer_name(kind) + " (remove " + checkpoint +
                             ".* to start over)");
  try {
    // LibTorch does not check the archives' CRCs: a damaged one would load,
    // train to NaN and replace the good model and checkpoint.
    for (const char* part : {".optimizer", ".evidence"})
      if (std::filesystem::exists(checkpoint + part)) check_model_archive(checkpoint + part);
  } catch (const ModelError& e) {
    throw std::runtime_error("cannot resume " + checkpoint + ": " + e.what() + " (remove " + checkpoint +
                             ".* to start over)");
  }
  try {
    resume_evidence_task(evidence, checkpoint, evidence_weight);
    torch::load(optimizer, checkpoint + ".optimizer");
  } catch (const c10::Error& e) {  // a file missing, cut short or of another run
    throw std::runtime_error("cannot resume " + checkpoint + ": its optimiser or side-task state cannot be read (" +
                             e.what_without_backtrace() + "; remove " + checkpoint + ".* to start over)");
  }
  spdlog::info("resuming from {} at step {}", checkpoint, step);
  report.best_before_resume = true;  // until a validation of this run beats it
  return step;
}

// One training batch's loss, accuracy and side-task loss.
struct StepResult {
  double loss, accuracy, evidence_loss;
};

// Running means of the training batches (exponential, 0.98 per step).
struct RunningMeans {
  double loss = 0, accuracy = 0, evidence = 0, window = 0;
  void add(const StepResult& batch) {
    loss = loss * 0.98 + batch.loss;
    accuracy = accuracy * 0.98 + batch.accuracy;
    evidence = evidence * 0.98 + batch.evidence_loss;
    window = window * 0.98 + 1.0;
  }
};

// The network, its side task and one optimiser over both, from scratch,
// from a given model (fine-tuning, --init) or from the last checkpoint
// (--resume); the optimiser is made for the network's final parameters.
struct Learner {
  std::shared_ptr<IntrospectionNetImpl> net;
  std::unique_ptr<EvidenceTask> evidence;
  std::unique_ptr<torch::optim::Optimizer> optimizer;
  int64_t first_step = 0;  // the checkpoint's step when resuming
};

// The files of a run's checkpoint are OUT.checkpoint.*.
std::string checkpoint_of(const TrainConfig& c) { return c.output + ".checkpoint"; }

// The model kept so far (best validated, or the last), uncalibrated: --out
// is written only once its gates are calibrated, so a run stopped part way
// leaves the model an earlier run wrote there as it was.
std::string kept_model_of(const TrainConfig& c) { return checkpoint_of(c) + ".kept"; }

std::unique_ptr<torch::optim::Optimizer> make_optimizer(const TrainConfig& c,
                                                        const std::vector<torch::Tensor>& parameters) {
  if (c.optimizer == Optimizer::kAdamW)
    return std::make_unique<torch::optim::AdamW>(
        parameters, torch::optim::AdamWOptions(c.learning_rate).weight_decay(c.weight_decay));
  return std::make_unique<torch::optim::SGD>(
      parameters, torch::optim::SGDOptions(c.learning_rate).momentum(c.momentum).weight_decay(c.weight_decay));
}

Learner make_learner(const TrainConfig& c, const SplitData& train, const ModelInfo& info, torch::Device device,
                     TrainReport& report) {
  const std::string checkpoint = checkpoint_of(c);
  const bool resuming = c.resume && std::filesystem::exists(checkpoint + ".model");
  Learner l;
  if (resuming || !c.init.empty()) {
    NativeModel start_from = load_native_model(resuming ? checkpoint + ".model" : c.init);
    check_can_start_from(start_from.info, info, resuming, c.output);
    if (resuming) check_resumed_recipe(start_from.info, c, train);
    l.net = start_from.net;
  } else {
    l.net = make_network(c.architecture, c.dropout, train.views);
  }
  l.net->to(device);
  l.evidence = make_evidence_task(c, train, *l.net, device);
  auto parameters = l.net->parameters();
  if (l.evidence)
    for (auto& p : l.evidence->parameters()) parameters.push_back(p);
  l.optimizer = make_optimizer(c, parameters);
  if (resuming)
    l.first_step = load_checkpoint(checkpoint, l.evidence.get(), c.evidence_weight, c.optimizer, *l.optimizer, report);
  if (resuming && l.first_step >= c.steps)  // nothing left to train: say so, not silently write the checkpoint
    spdlog::warn(
        "the checkpoint is at step {}, at or past --steps {}: no step is trained (give a larger --steps to train "
        "on)",
        l.first_step, c.steps);
  return l;
}

// One optimiser step on a batch: cross-entropy on the four classes, plus the side
// task's loss when there is one.
StepResult train_step(Learner& l, const TrainConfig& c, const SplitData& train, const std::vector<SampleRef>& batch,
                      BatchAugmenter& make_batch, int64_t step, torch::Device device) {
  l.net->train();
  const auto labels = labels_of(train, batch).to(device);
  const auto x = make_batch(patch_pointers(train, batch)).to(device);
  for (auto& group : l.optimizer->param_groups()) group.options().set_lr(learning_rate_at(c, step));
  l.optimizer->zero_grad();
  const auto features = l.net->features(x);
  const auto logits = l.net->head(features);
  auto loss = torch::nn::functional::cross_entropy(logits, labels);
  double evidence_loss = 0;
  if (l.evidence) {
    const auto e = l.evidence->loss(features, evidence_targets(train, batch, train.evidence_size).to(device));
    loss = loss + c.evidence_weight * e;
    evidence_loss = e.item<double>();
  }
  loss.backward();
  l.optimizer->step();
  return {loss.item<double>(), logits.argmax(1).eq(labels).to(torch::kFloat).mean().item<double>(), evidence_loss};
}

// A loss that is not finite poisons every weight from then on: stop, and
// say what is left (settings, not the data, are the likely cause).
// `what`: "the training loss is nan", or that the validation's outputs are not numbers.
[[noreturn]] void throw_diverged(const TrainConfig& c, const TrainReport& report, int64_t step,
                                 const std::string& what) {
  throw std::invalid_argument(fmt::format(
      "step {}: {}: training diverged (try a lower --lr than {}); {}", step, what, c.learning_rate,
      report.best_step > 0 ? fmt::format("{} holds the model kept at step {}, its gates not calibrated (ivoa-train "
                                         "--calibrate-only --init {} --out {} calibrates them)",
                                         kept_model_of(c), report.best_step, kept_model_of(c), c.output)
                           : std::string("no model was written")));
}

// What the progress callback sees after a step: the running means, the rate.
void update_status(TrainStatus& status, const RunningMeans& means, const TrainConfig& c, int64_t step,
                   bool has_evidence, double patches_per_s) {
  status.step = step + 1;
  status.loss = means.loss / means.window;
  status.accuracy = means.accuracy / means.window;
  status.evidence_loss = has_evidence ? means.evidence / means.window : -1;
  status.learning_rate = learning_rate_at(c, step);
  status.patches_per_s = patches_per_s;
}

// The report's record of the model kept: the best so far, or the last.
void record_kept(TrainReport& report, const LabelConfusion& val, int64_t step) {
  report.best_val_mean_class_accuracy = val.mean_per_class();
  report.best_val_accuracy = val.overall();
  for (int k = 0; k < kNumClasses; ++k) report.best_val_class_accuracy[static_cast<size_t>(k)] = val.recall(k);
  report.best_step = step;
  report.best_before_resume = false;
}

}  // namespace

const char* optimizer_name(Optimizer o) { return o == Optimizer::kAdamW ? "adamw" : "sgd"; }

void use_optimizer(TrainConfig& c, Optimizer o) {
  c.optimizer = o;
  c.learning_rate = o == Optimizer::kAdamW ? kAdamWLearningRate : kSgdLearningRate;
  c.weight_decay = o == Optimizer::kAdamW ? kAdamWWeightDecay : kSgdWeightDecay;
}

TrainReport calibrate_model(const TrainConfig& c) {
  const double start = monotonic_ms();
  torch::set_num_threads(std::max(c.threads, 1));
  if (c.init.empty() || c.output.empty()) throw std::runtime_error("calibration needs a model (--init) and --out");
  check_output_is_not_an_input(c);  // --init may be --out: it is read before the calibrated model is written
  make_output_folder(c.output);
  const torch::Device device = device_named(c.device);
  const SplitData val = load_split_data(c, c.val_split);
  NativeModel model = load_native_model(c.init);
  if (model.info.views != val.views || model.info.patch_scale != val.patch_scale ||
      model.info.patch_size != val.patch_size || model.info.detector != val.detector)
    throw std::runtime_error(
        fmt::format("{}: {} view(s), patch size {}, scale {}, detector '{}'; the validation sessions: {}, {}, {}, '{}'",
                    model.info.id, model.info.views, model.info.patch_size, model.info.patch_scale, model.info.detector,
                    val.views, val.patch_size, val.patch_scale, val.detector));
  model.net->to(device);
  auto generator = at::detail::createCPUGenerator(c.seed);
  const std::vector<SampleRef> refs = validation_subset(val, c.max_val_samples);
  TrainReport report;
  report.val_samples = static_cast<int64_t>(refs.size());
  calibrate_gates(model, val, refs, c, device, generator, report);
  save_model_or_throw(*model.net, model.info, c.output);  // weights and training summary unchanged
  report.seconds = (monotonic_ms() - start) / 1000.0;
  return report;
}

TrainReport train_model(const TrainConfig& c, const std::function<void(const TrainStatus&)>& progress) {
  const double start = monotonic_ms();
  torch::set_num_threads(std::max(c.threads, 1));
  torch::manual_seed(c.seed);
  const torch::Device device = device_named(c.device);
  if (c.output.empty()) throw std::runtime_error("no output model file given");
  if (c.val_split == c.train_split)
    throw std::invalid_argument("the validation split '" + c.val_split +
                                "' is the one trained on: the kept model and the uncertainty gate need held-out "
                                "sessions");
  check_output_is_not_an_input(c);
  make_output_folder(c.output);
  const SplitData train = load_split_data(c, c.train_split);
  const SplitData val = load_split_data(c, c.val_split);
  TrainReport report;
  const std::vector<int> classes = classes_present(train, report);
  if (static_cast<size_t>(c.batch_size) > train.size())
    spdlog::warn(
        "--batch-size {} is more than the {} training samples: every batch repeats them (the rarest class "
        "most, as batches are drawn class-balanced)",
        c.batch_size, train.size());
  ModelInfo info = model_info_for(c, train, val);
  Learner learner = make_learner(c, train, info, device, report);
  const int64_t first_step = learner.first_step;
  std::error_code ignored;
  if (first_step == 0) std::filesystem::remove(kept_model_of(c), ignored);  // an earlier run's

  // Every random stream continues from the step (a resumed run does not replay the first batches);
  // the sampler's and the augmenter's seeds are the run's times two primes, so no two streams coincide.
  BalancedSampler sampler(train, classes, c.fn_weight, c.seed * 7919 + static_cast<uint64_t>(first_step));
  auto generator = at::detail::createCPUGenerator(c.seed + static_cast<uint64_t>(first_step));
  PhotometricRanges ranges;
  ranges.noise_sigma = {0.0, c.augment_noise_max};
  BatchAugmenter make_batch(info, c.augment, c.seed * 104729 + static_cast<uint64_t>(first_step), ranges);
  const std::vector<SampleRef> val_refs = validation_subset(val, c.max_val_samples);
  report.val_samples = static_cast<int64_t>(val_refs.size());

  TrainStatus status;
  status.steps = c.steps;
  status.best_val_mean_class_accuracy = report.best_val_mean_class_accuracy;
  RunningMeans means;
  const double loop_start = monotonic_ms();
  for (int64_t step = first_step; step < c.steps; ++step) {
    const std::vector<SampleRef> batch = sampler.batch(c.batch_size);
    const StepResult result = train_step(learner, c, train, batch, make_batch, step, device);
    if (!std::isfinite(result.loss))
      throw_diverged(c, report, step + 1, fmt::format("the training loss is {}", result.loss));
    means.add(result);
    update_status(
        status, means, c, step, static_cast<bool>(learner.evidence),
        static_cast<double>((step + 1 - first_step) * c.batch_size) / ((monotonic_ms() - loop_start) / 1000.0));

    const bool last = step + 1 == c.steps;
    if ((step + 1) % c.validate_every == 0 || last) {
      const ValOutputs v = run_validation(*learner.net, val, val_refs, info, device, 1, generator);
      // Finite weights can still overflow on real input: such a model must not be kept.
      if (!v.outputs_finite)
        throw_diverged(c, report, step + 1, "the model's outputs on the validation patches are not numbers");
      status.val_mean_class_accuracy = v.confusion.mean_per_class();
      // The first validation is kept whatever it scores: a run must leave a model.
      const bool better = report.best_step == 0 || status.val_mean_class_accuracy > report.best_val_mean_class_accuracy;
      if (c.keep_last ? last : better) {
        record_kept(report, v.confusion, step + 1);
        info.training_summary = training_summary(c, train, val, report, step + 1);
        save_model_or_throw(*learner.net, info, kept_model_of(c));
      }
      status.best_val_mean_class_accuracy = report.best_val_mean_class_accuracy;
    }
    if ((step + 1) % c.checkpoint_every == 0 || last) {
      info.training_summary = training_summary(c, train, val, report, step + 1);  // what a resume is checked against
      save_checkpoint(checkpoint_of(c), *learner.net, info, learner.evidence.get(), c.optimizer, *learner.optimizer,
                      step + 1, report);
    }
    if (progress) progress(status);
  }

  // Calibrate the uncertainty gates of the model kept on validation data.
  // A checkpoint from before the kept model had a file of its own left it at --out.
  NativeModel best = load_native_model(std::filesystem::exists(kept_model_of(c)) ? kept_model_of(c) : c.output);
  best.net->to(device);
  calibrate_gates(best, val, val_refs, c, device, generator, report);
  best.info.training_summary = training_summary(c, train, val, report, report.best_step);
  save_model_or_throw(*best.net, best.info, c.output);
  report.last = status;
  report.seconds = (monotonic_ms() - start) / 1000.0;
  return report;
}

}  // namespace ivoa::introspection
