// Introspection benchmark: full-frame heatmaps with T MC-dropout passes on a
// 960x600 left image, next to the reference approach on the same frame in
// the same run (ut-amrl/IVOA: every 100x100 patch resized to 224, pushed
// through AlexNet T times, i.e. trunk included in every pass), and training
// throughput. The reference takes minutes per frame on a CPU, so it is
// timed on a sample of patches and scaled to the whole grid (its cost is
// linear in patches); the sample size is printed. The architectures are
// timed with random weights; the trained model (the shipped one unless
// --model) on its own input, as ivoa-introspection runs it.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <torch/torch.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "ivoa/introspection/model.hpp"
#include "ivoa/sim/sim_rig.hpp"
#include "augmentation.hpp"
#include "model_file.hpp"
#include "networks.hpp"
#include "tensors.hpp"

using namespace ivoa;
using namespace ivoa::introspection;

namespace {

cv::Mat test_frame() {
  // A real photograph if Debian's opencv-doc is installed (content does not
  // change the timing, but it keeps activations realistic).
  const std::string aloe = "/usr/share/doc/opencv-doc/examples/data/aloeL.jpg";
  cv::Mat image = std::filesystem::exists(aloe) ? cv::imread(aloe) : cv::Mat();
  if (image.empty()) {
    image = cv::Mat(600, 960, CV_8UC3);
    cv::randu(image, 0, 255);
  }
  cv::resize(image, image, cv::Size(960, 600));
  return image;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double time_ms(F f, int runs) {
  f();  // warm-up (allocations, oneDNN primitive creation)
  std::vector<double> t;
  for (int i = 0; i < runs; ++i) {
    const double s = monotonic_ms();
    f();
    t.push_back(monotonic_ms() - s);
  }
  return median(t);
}

// A network with random weights, saved as a model file.
std::string write_model(const std::string& architecture, const std::string& dir, int views = 1) {
  auto net = make_network(architecture, 0.5, views);
  ModelInfo info;
  info.architecture = architecture;
  info.input_size = input_size_of(architecture);
  info.views = views;
  const std::string path = dir + "/bench_" + architecture + std::to_string(views) + ".pt";
  save_model(*net, info, path);
  return path;
}

// ms per training step (forward, backward, SGD) of a batch of patches;
// channels_last=false runs SlideNet's trunk in PyTorch's default layout.
double train_step_ms(const std::string& architecture, int batch, int runs, int views = 1, bool channels_last = true) {
  auto net = make_network(architecture, 0.5, views);
  if (auto slide = std::dynamic_pointer_cast<SlideNetImpl>(net)) slide->channels_last = channels_last;
  net->train();
  torch::optim::SGD sgd(net->parameters(), torch::optim::SGDOptions(0.005).momentum(0.9));
  const int s = input_size_of(architecture);
  const auto x = torch::randn({batch, 3 * views, s, s});
  const auto y = torch::randint(0, 4, {batch}, torch::kLong);
  return time_ms(
      [&] {
        sgd.zero_grad();
        torch::nn::functional::cross_entropy(net->forward(x), y).backward();
        sgd.step();
      },
      runs);
}

// The augmentation as separate whole-batch tensor passes (how the trainer
// did it before BatchAugmenter, less its per-view gain, so the baseline is
// if anything a little cheaper): the baseline for the fused pass.
torch::Tensor tensor_pass_batch(const torch::Tensor& raw, const torch::Tensor& noise_bank, const ModelInfo& info) {
  const int64_t b = raw.size(0), s = raw.size(2), views = raw.size(1) / s;
  auto x = raw.view({b, views, s, s, 3})
               .flip({4})
               .permute({0, 1, 4, 2, 3})
               .reshape({b, 3 * views, s, s})
               .to(torch::kFloat)
               .div_(255.0);
  const auto mean = x.mean({1, 2, 3}, true);
  const auto contrast = torch::rand({b, 1, 1, 1}) * 0.6 + 0.7;
  const auto gain = (contrast * (torch::rand({b, 1, 1, 1}) * 0.8 + 0.6) * (torch::rand({b, 3, 1, 1}) * 0.2 + 0.9))
                        .repeat({1, views, 1, 1});
  auto y = torch::addcmul(mean * (1 - contrast) * gain / contrast, x, gain).clamp_(0, 1);
  y.pow_(torch::rand({b, 1, 1, 1}) * 0.45 + 0.8);
  y.add_(noise_bank.index_select(0, torch::randint(noise_bank.size(0), {b}, torch::kLong))
             .mul_(torch::rand({b, 1, 1, 1}) * 0.03));
  y.clamp_(0, 1);
  const auto m = torch::tensor({info.mean[0], info.mean[1], info.mean[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  const auto sd = torch::tensor({info.std[0], info.std[1], info.std[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  return ((y - m) / sd).contiguous();
}

// ms to turn `batch` raw two-view dataset patches into an augmented,
// normalised batch: {tensor passes, fused BatchAugmenter}.
std::pair<double, double> batch_preparation_ms(int batch, int runs) {
  ModelInfo info;
  info.views = 2;
  const int s = info.patch_size;
  const auto raw = torch::randint(0, 256, {batch, 2 * s, s, 3}, torch::kLong).to(torch::kUInt8);
  std::vector<const uint8_t*> patches;
  for (int i = 0; i < batch; ++i) patches.push_back(raw[i].data_ptr<uint8_t>());
  const auto noise_bank = torch::randn({BatchAugmenter::kNoiseBankSize, 6, s, s});
  BatchAugmenter fused(info, true, 1);
  return {time_ms([&] { tensor_pass_batch(raw, noise_bank, info); }, runs), time_ms([&] { fused(patches); }, runs)};
}

// The in-image query cells of the default grid with their footprint-scaled
// squares, as ivoa-introspection predicts them.
std::vector<IntrospectionModel::CellPatch> default_query_cells(const cv::Size& image) {
  const QueryGrid grid(QueryGridConfig{}, RigGeometry(sim::make_sim_rig()).left);
  const auto sides = footprint_patch_sides(make_obstacle_grid(grid, "jppc", 0), 100, image, 1.6);
  std::vector<IntrospectionModel::CellPatch> cells;
  for (int i = 0; i < grid.size(); ++i)
    if (grid.cell(i).in_image) cells.push_back({grid.cell(i).u, grid.cell(i).v, sides[static_cast<size_t>(i)]});
  return cells;
}

// ms per patch of the reference (each patch resized to 224, the whole
// AlexNet T times as one batch, MC dropout on), timed on the sample.
double reference_ms_per_patch(const std::vector<cv::Mat>& sample, int passes, int runs) {
  auto alexnet = make_network("alexnet", 0.5);
  alexnet->eval();
  alexnet->drop1->train();  // MC dropout on, as the reference does
  alexnet->drop2->train();
  ModelInfo alex_info;
  alex_info.architecture = "alexnet";
  alex_info.input_size = 224;
  const double sample_ms = time_ms(
      [&] {
        torch::NoGradGuard no_grad;
        for (const auto& patch : sample) {
          const auto x = patches_to_tensor({patch}, alex_info).repeat({passes, 1, 1, 1});  // T copies, one batch
          torch::softmax(alexnet->forward(x), -1).mean(0);
        }
      },
      runs);
  return sample_ms / static_cast<double>(sample.size());
}

// Patches spread evenly over the grid of 100 px patches at stride 20.
std::vector<cv::Mat> patch_sample(const cv::Mat& frame, int rows, int cols, int n) {
  std::vector<cv::Mat> sample;
  for (int k = 0; k < n; ++k) {
    const int cell = k * rows * cols / n;
    sample.push_back(frame(cv::Rect((cell % cols) * 20, (cell / cols) * 20, 100, 100)).clone());
  }
  return sample;
}

struct InferenceTimes {
  int rows = 0, cols = 0, near_cells = 0;
  double ours = 0, two_view = 0, trained = 0, alex = 0, reference = 0;  // ms per frame
  std::string model_name;                                               // the trained model, timed as `trained`
};

void print_inference(const InferenceTimes& t, int passes, int threads, int reference_patches) {
  std::printf("Introspection on a 960x600 frame: %d x %d = %d cells (100 px patches, stride 20), T = %d, %d threads\n",
              t.rows, t.cols, t.rows * t.cols, passes, threads);
  std::printf("  %-58s %10.1f ms/frame  (%.1f Hz)\n", "ours: slidenet, trunk once over the image, head x T batched",
              t.ours, 1000.0 / t.ours);
  std::printf("  %-58s %10.1f ms/frame  (%.1f Hz)\n", "ours, two views: ground warp + slidenet on 6 channels",
              t.two_view, 1000.0 / t.two_view);
  std::printf("  %-58s %10.1f ms/frame  (%.1f Hz)\n", t.model_name.c_str(), t.trained, 1000.0 / t.trained);
  std::printf("  %-58s %10.1f ms/frame  (from %d patches)\n", "alexnet-224, trunk once per patch, head x T batched",
              t.alex, reference_patches);
  std::printf("  %-58s %10.1f ms/frame  (from %d patches)\n", "reference: alexnet-224, whole network x T per patch",
              t.reference, reference_patches);
  const double worst_ms = std::max({t.ours, t.two_view, t.trained});
  std::printf(
      "  speed-up over the reference: %.0fx (one view), %.0fx (two views); budget 100 ms: %s (%.2f of budget)\n",
      t.reference / t.ours, t.reference / t.two_view, worst_ms <= 100.0 ? "met" : "NOT met", worst_ms / 100.0);
}

void print_training(int batch, int runs) {
  const double slide_step = train_step_ms("slidenet", batch, std::max(1, runs / 2));
  const double two_view_step = train_step_ms("slidenet", batch, std::max(1, runs / 2), 2);
  const double nchw_step = train_step_ms("slidenet", batch, std::max(1, runs / 2), 2, false);
  const int alex_batch = std::min(batch, 32);
  const double alex_step = train_step_ms("alexnet", alex_batch, 2);
  std::printf("Training throughput (forward + backward + SGD step):\n");
  std::printf("  %-58s %10.0f patches/s (batch %d)\n", "slidenet, 100x100 patches", 1000.0 * batch / slide_step, batch);
  std::printf("  %-58s %10.0f patches/s (batch %d)\n", "slidenet, two views", 1000.0 * batch / two_view_step, batch);
  std::printf("  %-58s %10.0f patches/s (channels-last: %.2fx faster)\n",
              "baseline: slidenet, two views, NCHW (PyTorch's default)", 1000.0 * batch / nchw_step,
              nchw_step / two_view_step);
  std::printf("  %-58s %10.0f patches/s (batch %d)\n", "alexnet-224, whole network", 1000.0 * alex_batch / alex_step,
              alex_batch);
  const auto [tensor_ms, fused_ms] = batch_preparation_ms(batch, runs);
  std::printf("Training batch preparation (%d two-view patches: decode, augment, normalise):\n", batch);
  std::printf("  %-58s %10.1f ms/batch\n", "baseline: whole-batch tensor passes", tensor_ms);
  std::printf("  %-58s %10.1f ms/batch  (%.1fx faster)\n", "ours: fused per-value tables (BatchAugmenter)", fused_ms,
              tensor_ms / fused_ms);
  std::printf("  %-58s %10.0f patches/s (with the baseline: %.0f)\n", "slidenet two views, step + batch preparation",
              1000.0 * batch / (two_view_step + fused_ms), 1000.0 * batch / (two_view_step + tensor_ms));
}

struct BenchOptions {
  int threads = 2, passes = 20, runs = 7, reference_patches = 16, batch = 128;
  std::string model = IVOA_SHIPPED_MODEL;
};

void add_bench_options(CLI::App& app, BenchOptions& o) {
  app.add_option("--threads", o.threads, "LibTorch threads")->capture_default_str()->check(ivoa::positive_number());
  app.add_option("--mc-passes", o.passes, "Monte-Carlo dropout passes (the paper's T)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--runs", o.runs, "timed runs (median reported)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--reference-patches", o.reference_patches, "patches the reference is timed on")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--batch", o.batch, "training batch")->capture_default_str()->check(ivoa::positive_number());
  app.add_option("--model", o.model,
                 "the trained model timed on its own input (views, footprint-scaled near cells); the other rows "
                 "time the architectures with random weights")
      ->capture_default_str();
}

// The trained model on the input it was trained for: the right view warped
// onto the ground if it has two, and the near cells' own squares if its
// patches are footprint-scaled. Throws ModelError on a bad file.
void time_trained_model(const cv::Mat& frame, const GroundWarp& warp, const BenchOptions& o,
                        const InferenceConfig& config, InferenceTimes& t) {
  const auto model = IntrospectionModel::load(o.model, config);
  const ModelInfo& info = model->info();
  std::vector<IntrospectionModel::CellPatch> query_cells;
  if (info.patch_scale > 0) query_cells = default_query_cells(frame.size());
  for (const auto& cell : query_cells) t.near_cells += cell.side > 100;
  t.model_name = std::filesystem::path(o.model).filename().string() + ", " + std::to_string(info.views) + " view" +
                 (info.views > 1 ? "s" : "") +
                 (query_cells.empty() ? "" : ", + " + std::to_string(t.near_cells) + " near cells' squares");
  introspection::Heatmaps h;
  t.trained = time_ms(
      [&] {
        const cv::Mat input = info.views == 2 ? warp.stack(frame, frame) : frame;
        h = model->run(input);
        if (!query_cells.empty()) model->predict_query_cells(input, h, query_cells);
      },
      o.runs);
}

// Our inference: the slidenet architecture with random weights on one and
// two views, then the trained model.
InferenceTimes time_ours(const cv::Mat& frame, const BenchOptions& o, const InferenceConfig& config,
                         const std::string& dir) {
  InferenceTimes t;
  introspection::Heatmaps h;
  const auto one_view = IntrospectionModel::load(write_model("slidenet", dir), config);
  t.ours = time_ms([&] { h = one_view->run(frame); }, o.runs);
  t.rows = h.rows;
  t.cols = h.cols;
  // Two views (the main job's and the shipped model's input): the right
  // image warped onto the ground, stacked under the left, 6 channels.
  const GroundWarp warp(sim::make_sim_rig());
  const auto two_view = IntrospectionModel::load(write_model("slidenet", dir, 2), config);
  t.two_view = time_ms([&] { h = two_view->run(warp.stack(frame, frame)); }, o.runs);
  time_trained_model(frame, warp, o, config, t);
  return t;
}

// The reference and our faithful AlexNet-224 option (trunk once per patch,
// head T times batched), both linear in patches: timed on a sample.
void time_reference(const cv::Mat& frame, const BenchOptions& o, const InferenceConfig& config, const std::string& dir,
                    InferenceTimes& t) {
  const std::vector<cv::Mat> sample = patch_sample(frame, t.rows, t.cols, o.reference_patches);
  const int cells = t.rows * t.cols;
  const int runs = std::max(1, o.runs / 3);
  t.reference = reference_ms_per_patch(sample, o.passes, runs) * cells;
  const auto alex_model = IntrospectionModel::load(write_model("alexnet", dir), config);
  t.alex = time_ms([&] { alex_model->run_patches(sample, false); }, runs) * cells / o.reference_patches;
}

}  // namespace

int main(int argc, char** argv) {
  ivoa::introspection::tune_libtorch_runtime(argv);
  CLI::App app{"Introspection benchmark: our full-frame MC-dropout inference vs the reference approach"};
  BenchOptions o;
  add_bench_options(app, o);
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;

  torch::set_num_threads(o.threads);
  const cv::Mat frame = test_frame();
  const std::string dir = std::filesystem::temp_directory_path().string();
  InferenceConfig config;
  config.mc_passes = o.passes;
  config.threads = o.threads;
  config.seed = 1;
  InferenceTimes t;
  try {
    t = time_ours(frame, o, config, dir);
  } catch (const ModelError& e) {
    std::fprintf(stderr, "ivoa-bench-introspection: %s\n", e.what());
    return kExitBadInput;
  }
  time_reference(frame, o, config, dir, t);
  print_inference(t, o.passes, o.threads, o.reference_patches);
  print_training(o.batch, o.runs);
  return kExitOk;
}
