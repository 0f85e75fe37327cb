#include "ivoa/introspection/model.hpp"

#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <utility>

#include <ATen/CPUGeneratorImpl.h>
#include <opencv2/imgproc.hpp>
#include <torch/script.h>

#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/time.hpp"
#include "mc_dropout.hpp"
#include "model_file.hpp"
#include "tensors.hpp"

namespace ivoa::introspection {
namespace {

constexpr int64_t kPatchBatch = 256;  // patches per forward when running patch by patch

torch::Generator make_generator(uint64_t seed) {
  return at::detail::createCPUGenerator(seed ? seed : static_cast<uint64_t>(now_utime()));
}

cv::Mat filtered(const cv::Mat& m, int window) {
  if (window <= 1) return m;
  cv::Mat out;
  cv::blur(m, out, cv::Size(window, window), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  return out;
}

// MC statistics of rows x cols cells -> the heatmaps, mean-filtered.
Heatmaps make_heatmaps(const McStats& stats, int rows, int cols, const ModelInfo& info, int window) {
  Heatmaps h;
  h.rows = rows;
  h.cols = cols;
  h.patch_size = info.patch_size;
  h.stride = info.stride;
  const auto mean = stats.mean.to(torch::kCPU), var = stats.variance.to(torch::kCPU);
  for (int c = 0; c < kNumClasses; ++c) {
    h.probability[static_cast<size_t>(c)] = filtered(to_mat(mean.select(1, c), rows, cols), window);
    h.variance[static_cast<size_t>(c)] = filtered(to_mat(var.select(1, c), rows, cols), window);
  }
  h.uncertainty = (h.variance[0] + h.variance[1] + h.variance[2] + h.variance[3]) / 4.0;
  h.predicted = cv::Mat(rows, cols, CV_8U);
  h.predicted_variance = cv::Mat(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      int best = 0;
      for (int k = 1; k < kNumClasses; ++k)
        if (h.probability[static_cast<size_t>(k)].at<float>(r, c) >
            h.probability[static_cast<size_t>(best)].at<float>(r, c))
          best = k;
      h.predicted.at<uint8_t>(r, c) = static_cast<uint8_t>(best);
      h.predicted_variance.at<float>(r, c) = h.variance[static_cast<size_t>(best)].at<float>(r, c);
    }
  const auto vmean = stats.verdict_mean.to(torch::kCPU), vvar = stats.verdict_variance.to(torch::kCPU);
  for (int k = 0; k < 2; ++k) {
    h.verdict_error[static_cast<size_t>(k)] = filtered(to_mat(vmean.select(1, k), rows, cols), window);
    h.verdict_error_variance[static_cast<size_t>(k)] = filtered(to_mat(vvar.select(1, k), rows, cols), window);
  }
  return h;
}

// mean, var: 4 classes; vmean, vvar: the 2 verdict errors.
Prediction prediction_of(const float* mean, const float* var, const float* vmean, const float* vvar, double threshold) {
  Prediction p;
  for (int k = 0; k < kNumClasses; ++k) {
    p.probability[static_cast<size_t>(k)] = mean[k];
    p.class_variance[static_cast<size_t>(k)] = var[k];
  }
  for (size_t k = 0; k < 2; ++k) {
    p.verdict_error[k] = vmean[k];
    p.verdict_error_variance[k] = vvar[k];
  }
  p.predicted = static_cast<int>(std::max_element(mean, mean + kNumClasses) - mean);
  p.variance = var[p.predicted];
  p.uncertainty = (var[0] + var[1] + var[2] + var[3]) / 4.0f;
  p.announced = p.variance <= threshold;
  return p;
}

void append_predictions(const McStats& s, double threshold, std::vector<Prediction>& out) {
  const auto cpu = [](const torch::Tensor& t) { return t.to(torch::kCPU).contiguous(); };
  const auto mean = cpu(s.mean), var = cpu(s.variance), vmean = cpu(s.verdict_mean), vvar = cpu(s.verdict_variance);
  for (int64_t i = 0; i < mean.size(0); ++i)
    out.push_back(prediction_of(mean[i].data_ptr<float>(), var[i].data_ptr<float>(), vmean[i].data_ptr<float>(),
                                vvar[i].data_ptr<float>(), threshold));
}

// All patches of the heatmap grid (views stacked), for models that run patch by patch.
std::vector<cv::Mat> grid_patches(const cv::Mat& image, const ModelInfo& info, int& rows, int& cols) {
  const int height = image.rows / info.views;
  rows = (height - info.patch_size) / info.stride + 1;
  cols = (image.cols - info.patch_size) / info.stride + 1;
  std::vector<cv::Mat> patches;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      std::vector<cv::Mat> views;
      for (int k = 0; k < info.views; ++k)
        views.push_back(
            image(cv::Rect(c * info.stride, k * height + r * info.stride, info.patch_size, info.patch_size)));
      cv::Mat stacked;
      if (info.views == 1) stacked = views[0];
      else cv::vconcat(views, stacked);
      patches.push_back(stacked);
    }
  return patches;
}

void check_image(const cv::Mat& image, const ModelInfo& info) {
  if (image.type() != CV_8UC3) throw ModelError("introspection needs an 8-bit BGR image");
  if (info.views > 1 && image.rows % info.views != 0)
    throw ModelError("a " + std::to_string(info.views) + "-view model needs its views stacked: " +
                     std::to_string(image.rows) + " rows is not a multiple of " + std::to_string(info.views));
  if (image.rows / info.views < info.patch_size || image.cols < info.patch_size)
    throw ModelError("image " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     " is smaller than one patch");
}

class NativeIntrospectionModel : public IntrospectionModel {
 public:
  NativeIntrospectionModel(NativeModel model, const InferenceConfig& config)
      : IntrospectionModel(config),
        model_(std::move(model)),
        device_(device_named(config.device)),
        generator_(make_generator(config.seed)) {
    model_.net->to(device_);
    model_.net->eval();
  }
  const ModelInfo& info() const override { return model_.info; }

  Heatmaps run(const cv::Mat& image) override {
    check_image(image, model_.info);
    torch::NoGradGuard no_grad;
    const double start = monotonic_ms();
    int64_t rows = 0, cols = 0;
    torch::Tensor features;
    if (auto* slide = dynamic_cast<SlideNetImpl*>(model_.net.get())) {
      features = slide->cell_features(image_to_tensor(image, model_.info).to(device_), rows, cols);
    } else {
      int r = 0, c = 0;
      features = patch_features(grid_patches(image, model_.info, r, c));
      rows = r;
      cols = c;
    }
    Heatmaps h =
        make_heatmaps(head(features), static_cast<int>(rows), static_cast<int>(cols), model_.info, config_.mean_filter);
    h.compute_ms = monotonic_ms() - start;
    return h;
  }

  PatchOutputs run_patches(const std::vector<cv::Mat>& patches, bool with_embeddings) override {
    torch::NoGradGuard no_grad;
    PatchOutputs out;
    for (size_t begin = 0; begin < patches.size(); begin += kPatchBatch) {
      const std::vector<cv::Mat> batch(
          patches.begin() + static_cast<long>(begin),
          patches.begin() + static_cast<long>(std::min(patches.size(), begin + kPatchBatch)));
      const auto features = patch_features(batch);
      const McStats s = head(features);
      append_predictions(s, uncertainty_threshold(), out.predictions);
      if (with_embeddings) {
        const auto e = model_.net->embedding(features).to(torch::kCPU).contiguous();
        for (int64_t i = 0; i < e.size(0); ++i)
          out.embeddings.emplace_back(e[i].data_ptr<float>(), e[i].data_ptr<float>() + e.size(1));
      }
    }
    return out;
  }

 private:
  torch::Tensor patch_features(const std::vector<cv::Mat>& patches) {
    std::vector<torch::Tensor> parts;
    for (size_t begin = 0; begin < patches.size(); begin += kPatchBatch) {
      const std::vector<cv::Mat> batch(
          patches.begin() + static_cast<long>(begin),
          patches.begin() + static_cast<long>(std::min(patches.size(), begin + kPatchBatch)));
      parts.push_back(model_.net->features(patches_to_tensor(batch, model_.info).to(device_)));
    }
    return torch::cat(parts);
  }
  McStats head(const torch::Tensor& features) {
    return config_.mc_passes > 1 ? mc_dropout_head(*model_.net, features, config_.mc_passes, generator_)
                                 : deterministic_head(*model_.net, features);
  }

  NativeModel model_;
  torch::Device device_;
  torch::Generator generator_;
};

// An externally scripted TorchScript model (see README): forward() maps
// normalised [B, 3, S, S] patches to logits [B, 4]; MC dropout runs the
// whole model T times with only its Dropout modules in training mode.
class ScriptedIntrospectionModel : public IntrospectionModel {
 public:
  ScriptedIntrospectionModel(torch::jit::Module module, ModelInfo info, const InferenceConfig& config)
      : IntrospectionModel(config), module_(std::move(module)), info_(std::move(info)) {
    module_.eval();
    for (auto m : module_.modules())
      if (m.type()->name() && m.type()->name()->name().find("Dropout") != std::string::npos) m.train(true);
    torch::manual_seed(config.seed ? config.seed : static_cast<uint64_t>(now_utime()));
  }
  const ModelInfo& info() const override { return info_; }

  Heatmaps run(const cv::Mat& image) override {
    check_image(image, info_);
    const double start = monotonic_ms();
    int rows = 0, cols = 0;
    const McStats s = stats(grid_patches(image, info_, rows, cols));
    Heatmaps h = make_heatmaps(s, rows, cols, info_, config_.mean_filter);
    h.compute_ms = monotonic_ms() - start;
    return h;
  }

  PatchOutputs run_patches(const std::vector<cv::Mat>& patches, bool with_embeddings) override {
    if (with_embeddings) throw ModelError(info_.id + ": scripted models do not provide embeddings");
    const McStats s = stats(patches);
    PatchOutputs out;
    append_predictions(s, uncertainty_threshold(), out.predictions);
    return out;
  }

 private:
  McStats stats(const std::vector<cv::Mat>& patches) {
    torch::NoGradGuard no_grad;
    const int passes = std::max(config_.mc_passes, 1);
    std::vector<torch::Tensor> all;
    for (size_t begin = 0; begin < patches.size(); begin += kPatchBatch) {
      const std::vector<cv::Mat> batch(
          patches.begin() + static_cast<long>(begin),
          patches.begin() + static_cast<long>(std::min(patches.size(), begin + kPatchBatch)));
      const auto x = patches_to_tensor(batch, info_);
      std::vector<torch::Tensor> runs;
      for (int t = 0; t < passes; ++t) runs.push_back(torch::softmax(module_.forward({x}).toTensor(), -1));
      all.push_back(torch::stack(runs));  // [T, B, 4]
    }
    return summarise_passes(torch::cat(all, 1));
  }

  torch::jit::Module module_;
  ModelInfo info_;
};

std::unique_ptr<IntrospectionModel> load_scripted(const std::string& path, const InferenceConfig& config) {
  torch::jit::Module module;
  try {
    module = torch::jit::load(path);
  } catch (const c10::Error& e) {
    throw ModelError(path + ": not a TorchScript model (" + std::string(e.what_without_backtrace()).substr(0, 200) +
                     ")");
  }
  if (!module.find_method("forward")) throw ModelError(path + ": scripted model has no forward()");
  if (!module.hasattr(kMetadataKey))
    throw ModelError(path + ": scripted model has no '" + std::string(kMetadataKey) +
                     "' buffer (JSON metadata as a uint8 tensor; see README)");
  const auto t = module.attr(kMetadataKey).toTensor().contiguous();
  ModelInfo info = info_from_json(
      std::string(reinterpret_cast<const char*>(t.data_ptr<uint8_t>()), static_cast<size_t>(t.numel())), path);
  info.id = path;
  return std::make_unique<ScriptedIntrospectionModel>(std::move(module), std::move(info), config);
}

}  // namespace

namespace {

// A process takes its name (ps, top, pkill) from the file executed: after
// the re-execution through /proc/self/exe it is "exe". It is given the name
// of the file first executed back, which argv[0] names (a link's name
// included); failing that, the binary's own.
void name_after_invocation(char** argv) {
  std::ifstream comm("/proc/self/comm");
  std::string name;
  if (!std::getline(comm, name) || name != "exe") return;
  std::string invoked = argv && argv[0] ? std::filesystem::path(argv[0]).filename().string() : "";
  if (invoked.empty()) {
    std::error_code error;
    invoked = std::filesystem::read_symlink("/proc/self/exe", error).filename().string();
    if (const size_t deleted = invoked.find(" (deleted)"); deleted != std::string::npos) invoked.resize(deleted);
  }
  if (!invoked.empty()) prctl(PR_SET_NAME, invoked.substr(0, 15).c_str(), 0, 0, 0);
}

}  // namespace

void tune_libtorch_runtime(char** argv) {
  // Thresholds above any tensor: nothing is mapped per allocation, nothing
  // handed back to the kernel between steps.
  constexpr const char* kMallocTunables =
      "glibc.malloc.mmap_threshold=2147483647:glibc.malloc.trim_threshold=4294967295";
  bool changed = false;
  for (const auto& [name, value] :
       {std::pair{"OMP_WAIT_POLICY", "PASSIVE"}, std::pair{"GLIBC_TUNABLES", kMallocTunables}})
    if (std::getenv(name) == nullptr && setenv(name, value, 1) == 0) changed = true;
  if (!changed) return name_after_invocation(argv);
  // Through /proc/self/exe: it still reaches the running binary after a
  // rebuild replaced the file or a move renamed it.
  execv("/proc/self/exe", argv);
  // execv only returns on failure: then run with the defaults
}

std::unique_ptr<IntrospectionModel> IntrospectionModel::load(const std::string& path, const InferenceConfig& config) {
  if (config.mc_passes < 1) throw ModelError("mc_passes must be >= 1");
  if (config.mean_filter < 1 || config.mean_filter % 2 == 0) throw ModelError("mean_filter must be odd and >= 1");
  torch::set_num_threads(std::max(config.threads, 1));
  check_model_archive(path);  // native and scripted files alike
  std::string json;
  bool native = false;
  try {
    native = read_metadata(path, json) && info_from_json(json, path).architecture != "scripted";
  } catch (const c10::Error&) {
  }
  if (native) return std::make_unique<NativeIntrospectionModel>(load_checked_native_model(path), config);
  return load_scripted(path, config);
}

bool trained_on_size(const ModelInfo& info, cv::Size size) {
  return info.image_sizes.empty() ||
         std::find(info.image_sizes.begin(), info.image_sizes.end(), size) != info.image_sizes.end();
}

std::string image_sizes_text(const std::vector<cv::Size>& sizes) {
  if (sizes.empty()) return "not recorded";
  std::string text;
  for (const cv::Size& s : sizes)
    text += (text.empty() ? "" : ", ") + std::to_string(s.width) + "x" + std::to_string(s.height);
  return text;
}

std::string image_sizes_json(const std::vector<cv::Size>& sizes) {
  std::string json;
  for (const cv::Size& s : sizes)
    json += (json.empty() ? "" : ", ") + ("[" + std::to_string(s.width) + ", " + std::to_string(s.height) + "]");
  return "[" + json + "]";
}

double IntrospectionModel::uncertainty_threshold() const {
  return config_.uncertainty_threshold >= 0 ? config_.uncertainty_threshold : info().uncertainty_threshold;
}

double IntrospectionModel::verdict_threshold() const {
  if (config_.verdict_uncertainty_threshold >= 0) return config_.verdict_uncertainty_threshold;
  return info().verdict_uncertainty_threshold >= 0 ? info().verdict_uncertainty_threshold
                                                   : info().uncertainty_threshold;
}

std::vector<Prediction> IntrospectionModel::predict_cells(const cv::Mat& image, const std::vector<CellPatch>& cells) {
  check_image(image, info());
  if (cells.empty()) return {};
  const auto patches = cut_patches(image, info().views, cells, info().patch_size, config_.threads > 1);
  for (size_t i = 0; i < cells.size(); ++i)
    if (patches[i].empty())
      throw ModelError("the " + std::to_string(cells[i].side) + " px patch around (" + std::to_string(cells[i].u) +
                       ", " + std::to_string(cells[i].v) + ") leaves the image");
  return run_patches(patches, false).predictions;
}

std::vector<Prediction> IntrospectionModel::predict_query_cells(const cv::Mat& image, const Heatmaps& h,
                                                                const std::vector<CellPatch>& cells) {
  std::vector<Prediction> out(cells.size());
  std::vector<size_t> scaled;
  std::vector<CellPatch> squares;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i].side > info().patch_size) {
      scaled.push_back(i);
      squares.push_back(cells[i]);
    } else {
      out[i] = predict_at(h, cells[i].u, cells[i].v);
    }
  }
  const auto own = predict_cells(image, squares);
  for (size_t k = 0; k < scaled.size(); ++k) out[scaled[k]] = own[k];
  return out;
}

Prediction IntrospectionModel::predict_at(const Heatmaps& h, double u, double v) const {
  const double fc = (u - h.patch_size / 2.0) / h.stride, fr = (v - h.patch_size / 2.0) / h.stride;
  std::function<float(const cv::Mat&)> read;
  if (config_.lookup == QueryLookup::kNearest) {
    const int c = std::clamp(static_cast<int>(std::lround(fc)), 0, h.cols - 1);
    const int r = std::clamp(static_cast<int>(std::lround(fr)), 0, h.rows - 1);
    read = [r, c](const cv::Mat& m) { return m.at<float>(r, c); };
  } else {
    const cv::Point2f at(static_cast<float>(std::clamp(fc, 0.0, h.cols - 1.0)),
                         static_cast<float>(std::clamp(fr, 0.0, h.rows - 1.0)));
    read = [at](const cv::Mat& m) {
      cv::Mat patch;
      cv::getRectSubPix(m, {1, 1}, at, patch);
      return patch.at<float>(0, 0);
    };
  }
  std::array<float, kNumClasses> mean{}, var{};
  for (size_t k = 0; k < kNumClasses; ++k) {
    mean[k] = read(h.probability[k]);
    var[k] = read(h.variance[k]);
  }
  std::array<float, 2> vmean{}, vvar{};
  for (size_t k = 0; k < 2; ++k) {
    vmean[k] = read(h.verdict_error[k]);
    vvar[k] = read(h.verdict_error_variance[k]);
  }
  return prediction_of(mean.data(), var.data(), vmean.data(), vvar.data(), uncertainty_threshold());
}

VerdictPrediction given_verdict(const Prediction& p, bool said_obstacle, double threshold) {
  const size_t k = said_obstacle ? 0 : 1;
  VerdictPrediction v;
  v.p_wrong = p.verdict_error[k];
  v.variance = p.verdict_error_variance[k];
  const bool wrong = v.p_wrong > 0.5f;
  v.predicted = said_obstacle ? (wrong ? 2 : 0) : (wrong ? 3 : 1);  // FP / TP, FN / TN
  v.announced = v.variance <= threshold;
  return v;
}

}  // namespace ivoa::introspection
