#pragma once
// Training an introspection model on a dataset (libs/dataset format) with
// session splits. Defaults follow the paper and the reference code where
// they are known (dropout 0.5, class-balanced sampling with replacement;
// their SGD, lr 0.005, momentum 0.9, is one option away); a CPU needs a
// smaller batch than the reference's 2048, and the reference has no
// schedule, seeds, augmentation or AdamW, which we add.
#include <array>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ivoa::introspection {

// SGD with momentum is the paper's; AdamW (Adam with decoupled weight
// decay), the default, trains this network from scratch further in the
// same steps (docs/accuracy.md: +1 to +2 points held out).
enum class Optimizer { kSgd, kAdamW };
const char* optimizer_name(Optimizer o);  // "sgd", "adamw"
// Each optimiser's default learning rate and weight decay.
inline constexpr double kAdamWLearningRate = 0.001, kAdamWWeightDecay = 0.05;  // decoupled
inline constexpr double kSgdLearningRate = 0.005, kSgdWeightDecay = 5e-4;      // paper / reference; L2

struct TrainConfig {
  std::string dataset;     // dataset folder
  std::string split_file;  // YAML: split name -> sessions
  std::string train_split = "train";
  std::string val_split = "val";
  std::string output;  // model file to write (the best model, or the last with keep_last)
  std::string architecture = "slidenet";
  std::string init;     // optional model file to start from (fine-tuning)
  bool resume = false;  // continue from output + ".checkpoint" if present

  int64_t steps = 4000;  // optimiser steps
  int batch_size = 128;
  // use_optimizer() sets the optimiser with its own learning rate and
  // weight decay; these are AdamW's.
  Optimizer optimizer = Optimizer::kAdamW;
  double learning_rate = kAdamWLearningRate;
  double momentum = 0.9;                    // paper / reference; SGD only
  double weight_decay = kAdamWWeightDecay;  // AdamW: per step times the learning rate; SGD: L2 in the gradient
  int64_t warmup_steps = 200;               // linear warm-up, then cosine decay to 1% (reference: constant)
  double dropout = 0.5;
  // Class-balanced sampling: each class is drawn equally often; the FN
  // class's share is multiplied by this (the reference uses 0.1 outdoors).
  double fn_weight = 1.0;
  bool augment = true;  // photometric: brightness, contrast, gamma, channel gains, noise
  // Upper end of the augmentation's per-pixel Gaussian noise (sigma on [0, 1],
  // drawn uniformly from 0 to it). Unlike the gains, added noise changes what
  // the stereo matcher would see, while the label stays the recorded one.
  double augment_noise_max = 0.03;
  // Weight of the side task (evidence_task.hpp) in the loss: regress the
  // detector's evidence stored with each sample; 0 turns it off, and
  // datasets without evidence train without it.
  double evidence_weight = 5.0;
  uint64_t seed = 1;
  int threads = 2;
  std::string device = "cpu";
  int64_t validate_every = 250;
  // Write the final step's model instead of the best-validated one. With a
  // few validation sessions the best step is partly chance, and it is often
  // a mid-run one whose learning rate is still high.
  bool keep_last = false;
  int64_t checkpoint_every = 500;
  int64_t max_val_samples = 20000;  // validation subset (deterministic, spread over sessions)
  // The uncertainty gate stored in the model: the predicted-class variance
  // below which this fraction of validation samples is retained.
  double threshold_retain = 0.7;
  int threshold_passes = 20;  // MC-dropout passes for it: as InferenceConfig::mc_passes will run it
};

// The optimiser with its default learning rate and weight decay.
void use_optimizer(TrainConfig& c, Optimizer o);

struct TrainStatus {
  int64_t step = 0, steps = 0;
  double loss = 0;      // running mean
  double accuracy = 0;  // running mean, training batches
  double learning_rate = 0;
  double patches_per_s = 0;
  double evidence_loss = -1;            // running mean of the side task's loss (-1: off)
  double val_mean_class_accuracy = -1;  // last validation (-1 before the first)
  double best_val_mean_class_accuracy = -1;
};

struct TrainReport {
  TrainStatus last;
  // best_*: the validation of the model written, the best one (or, with
  // keep_last, the final one).
  int64_t best_step = 0;
  double best_val_mean_class_accuracy = 0;
  double best_val_accuracy = 0;
  std::array<double, 4> best_val_class_accuracy{};  // NaN for a class the validation samples lack
  // The best model is from before a --resume (this run never beat it): only
  // its step and mean per-class accuracy are known (the checkpoint's).
  bool best_before_resume = false;
  double uncertainty_threshold = 0;
  double val_accuracy_retained = 0;  // mean per-class accuracy of the retained val samples
  // The same for the predictions given the detector's verdict (given_verdict).
  double verdict_uncertainty_threshold = 0;
  double val_verdict_accuracy_retained = 0;
  std::array<int64_t, 4> train_class_counts{};
  int64_t val_samples = 0;
  double seconds = 0;
};

// A model or checkpoint file that cannot be written (no such folder, disk
// full, permissions): the tool's exit code says I/O error, not bad input.
class TrainOutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Trains and writes config.output, creating its folder. Throws
// TrainOutputError for a file it cannot write, std::invalid_argument for
// settings that cannot train (validation on the training split),
// std::runtime_error naming any other problem (missing split, empty class,
// unreadable dataset, a device LibTorch cannot use).
TrainReport train_model(const TrainConfig& config, const std::function<void(const TrainStatus&)>& progress = {});

// Re-calibrates the uncertainty gates of an existing model (config.init) on
// the validation split, at config.threshold_retain, and writes it to
// config.output with its weights and training summary unchanged. Fills the
// report's thresholds, val_accuracy_retained fields, val_samples, seconds.
TrainReport calibrate_model(const TrainConfig& config);

}  // namespace ivoa::introspection
