#pragma once
// The introspection model: a CNN that predicts, per image patch, whether the
// stereo detector's verdict there is a TP, TN, FP or FN, with Monte-Carlo
// dropout uncertainty. LibTorch stays behind this header.
//
// Full-frame inference gives the paper's heatmaps: the left image is cut
// into patch_size x patch_size patches at `stride` (cell (r, c) is the patch
// whose top-left corner is (c * stride, r * stride)), each patch gets the
// mean class probabilities over T dropout passes and their variance. For a
// 960x600 image with 100 px patches at stride 20 that is 26 rows x 44
// columns: floor((600-100)/20)+1 by floor((960-100)/20)+1. The paper's
// "49 x 26" would need the image padded by 50 px left and right; we do not
// pad (no patch sees invented pixels).
#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/labels.hpp"
#include "ivoa/core/patch_square.hpp"

namespace ivoa::introspection {

inline constexpr int kNumClasses = kNumLabels;  // kLabelNames' order

class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a model file says about itself.
struct ModelInfo {
  std::string architecture;  // "slidenet" (default) or "alexnet" or "scripted"
  std::string detector;      // the perception model it was trained to introspect
  int patch_size = 100;      // pixels of the left image per patch
  int stride = 20;           // heatmap stride, pixels
  int input_size = 100;      // patches are resized to this before the network
  // 1: the left image (the paper). 2: the left image and, stacked below it,
  // the right image warped onto the ground plane (core's GroundWarp), so
  // the network sees what the stereo matcher compares.
  int views = 1;
  // 0: fixed patch_size squares. > 0: trained on footprint-scaled patches
  // (core's footprint_patch.hpp): query cells must be predicted from squares
  // cut the same way (predict_cells); the heatmaps still use fixed squares,
  // which equal the scaled ones wherever the disc fits in patch_size.
  double patch_scale = 0;
  // The left-image sizes (width x height, pixels) of the cameras the
  // training sessions came from; empty for models written before they were
  // recorded or trained on sessions that do not say. Patches are cut in the
  // ground frame and resized, so another size runs, but nothing measured
  // how well: the tools say so (trained_on_size).
  std::vector<cv::Size> image_sizes;
  double dropout = 0.5;
  std::array<float, 3> mean{0.485f, 0.456f, 0.406f};  // RGB, on [0, 1]
  std::array<float, 3> std{0.229f, 0.224f, 0.225f};
  std::vector<std::string> classes{kLabelNames.begin(), kLabelNames.end()};
  double uncertainty_threshold = 0.01;  // recommended gate (predicted-class variance)
  // Gate of the predictions given the detector's verdict (given_verdict):
  // the variance of P(wrong | verdict) calibrated like uncertainty_threshold;
  // < 0 for models calibrated before it existed (uncertainty_threshold is used).
  double verdict_uncertainty_threshold = -1;
  std::string training_summary;  // JSON: data, steps, validation metrics
  std::string id;                // file name and content hash
};

// Whether `size` is one the model was trained on; true when the model does
// not say (ModelInfo::image_sizes empty).
bool trained_on_size(const ModelInfo& info, cv::Size size);
// "960x600" or "960x600, 640x480"; "not recorded" when empty.
std::string image_sizes_text(const std::vector<cv::Size>& sizes);
// As JSON: "[[960, 600], [640, 480]]".
std::string image_sizes_json(const std::vector<cv::Size>& sizes);

enum class QueryLookup { kNearest, kBilinear };

struct InferenceConfig {
  int mc_passes = 20;                         // T
  int threads = 2;                            // LibTorch intra-op threads (it defaults to 1 on this kind of machine)
  int mean_filter = 3;                        // odd window of the mean filter over each heatmap; 1 = off
  double uncertainty_threshold = -1;          // < 0: the model's recommended value
  double verdict_uncertainty_threshold = -1;  // gate given the verdict; < 0: the model's (verdict_threshold())
  QueryLookup lookup = QueryLookup::kNearest;
  uint64_t seed = 0;           // dropout masks; 0 = from the clock
  std::string device = "cpu";  // "cpu" or "cuda" (LibTorch built with CUDA)
};

// Heatmaps of one frame, rows x cols, CV_32F. Probabilities and variances
// are mean-filtered (InferenceConfig::mean_filter).
struct Heatmaps {
  int rows = 0, cols = 0, patch_size = 0, stride = 0;
  std::array<cv::Mat, kNumClasses> probability;  // mean over passes
  std::array<cv::Mat, kNumClasses> variance;     // variance over passes (n - 1)
  cv::Mat uncertainty;                           // mean over classes of the variance (the paper's heatmap)
  cv::Mat predicted;                             // CV_8U, argmax class
  cv::Mat predicted_variance;                    // variance of the predicted class's probability (the gate)
  // Prediction::verdict_error and its variance: [0] P(FP | obstacle), [1] P(FN | free).
  std::array<cv::Mat, 2> verdict_error, verdict_error_variance;
  double compute_ms = 0;
};

struct Prediction {
  int predicted = 0;  // class index
  std::array<float, kNumClasses> probability{};
  std::array<float, kNumClasses> class_variance{};  // per class, over passes
  float variance = 0;                               // of the predicted class (the gate)
  float uncertainty = 0;                            // mean over classes
  bool announced = false;                           // variance <= threshold
  // The detector's verdict at the cell is known at run time, and it leaves
  // two of the four classes possible: the question a planner asks is whether
  // that verdict is wrong. Mean and variance over the passes of
  // [0] P(FP | it said obstacle) = p_FP / (p_TP + p_FP) and
  // [1] P(FN | it said free) = p_FN / (p_TN + p_FN), taken pass by pass.
  std::array<float, 2> verdict_error{};
  std::array<float, 2> verdict_error_variance{};
};

// A prediction given the detector's verdict: TP or FP where it said
// obstacle, TN or FN where it said free.
struct VerdictPrediction {
  int predicted = 0;       // class index
  float p_wrong = 0;       // P(FP | obstacle) or P(FN | free)
  float variance = 0;      // of p_wrong over the passes (the gate)
  bool announced = false;  // variance <= threshold
};
VerdictPrediction given_verdict(const Prediction& p, bool said_obstacle, double threshold);

// Per-patch outputs (evaluation, clustering).
struct PatchOutputs {
  std::vector<Prediction> predictions;
  std::vector<std::vector<float>> embeddings;  // FC2 (256-d, post-ReLU, no dropout), if asked
};

// Two settings LibTorch's CPU path needs, read only when the program is
// loaded, so this re-executes the program once with them (each unless the
// user set it). Call it first thing in main().
// - OMP_WAIT_POLICY=PASSIVE: LibTorch's OpenMP threads otherwise spin while
//   they wait for work, which on a robot computer shared with other
//   processes is ruinous (measured 5x slower under load).
// - GLIBC_TUNABLES keeping freed memory for reuse: by default glibc maps
//   every large tensor afresh and unmaps it when freed, and the kernel's
//   page faults then took three quarters of a training step (ivoa-train
//   4.2x faster without them; the same model byte for byte).
void tune_libtorch_runtime(char** argv);

class IntrospectionModel {
 public:
  // Loads a model file written by ivoa-train (or an externally scripted
  // TorchScript model, see README). Throws ModelError naming the file and
  // what is wrong with it.
  static std::unique_ptr<IntrospectionModel> load(const std::string& path, const InferenceConfig& config = {});
  virtual ~IntrospectionModel() = default;

  virtual const ModelInfo& info() const = 0;
  // The gate of the four-class predictions: the configured threshold if set,
  // else the model's uncertainty_threshold.
  double uncertainty_threshold() const;
  // The gate of given_verdict(): the configured threshold if set, else the
  // model's verdict_uncertainty_threshold, else its uncertainty_threshold.
  double verdict_threshold() const;

  // Full-frame heatmaps of a left image (8-bit BGR); for a two-view model,
  // the left image stacked over the ground-warped right one (2 x height rows).
  virtual Heatmaps run(const cv::Mat& image) = 0;
  // The prediction at image point (u, v) from the heatmaps.
  Prediction predict_at(const Heatmaps& heatmaps, double u, double v) const;

  // Patches (patch_size square, 8-bit BGR; views stacked for a two-view
  // model, as the dataset stores them); MC dropout when mc_passes > 1.
  virtual PatchOutputs run_patches(const std::vector<cv::Mat>& patches, bool with_embeddings) = 0;

  // Predictions at query cells from their own patches: the side x side
  // square around (u, v) of the model input (views stacked, as for run()),
  // resized to patch_size. What a footprint-scaled model needs; side =
  // patch_size gives the heatmap's patch at that point without the mean
  // filter. Throws ModelError for a square that leaves the image.
  using CellPatch = PatchSquare;
  std::vector<Prediction> predict_cells(const cv::Mat& image, const std::vector<CellPatch>& cells);
  // Query cells as ivoa-introspection predicts them: a cell whose square is
  // larger than patch_size (a footprint-scaled model's near cells) from its
  // own square (predict_cells), every other cell from the heatmaps
  // (predict_at), so only the scaled cells cost a network pass.
  std::vector<Prediction> predict_query_cells(const cv::Mat& image, const Heatmaps& heatmaps,
                                              const std::vector<CellPatch>& cells);

 protected:
  explicit IntrospectionModel(InferenceConfig config) : config_(config) {}
  InferenceConfig config_;
};

}  // namespace ivoa::introspection
