// ivoa-train: dataset + split file -> introspection model file.
//
//   ivoa-train --dataset data/ --split split.yaml --out model.pt
#include <cstdio>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/progress.hpp"
#include "ivoa/introspection/model.hpp"
#include "ivoa/introspection/training.hpp"

using namespace ivoa;

namespace {

void print_gates(const introspection::TrainReport& r, const introspection::TrainConfig& c) {
  std::printf("uncertainty gate %.3g keeps %.0f%% of validation at mean per-class accuracy %.3f\n",
              r.uncertainty_threshold, 100 * c.threshold_retain, r.val_accuracy_retained);
  std::printf("given the detector's verdict: gate %.3g keeps %.0f%% of validation at mean per-class accuracy %.3f\n",
              r.verdict_uncertainty_threshold, 100 * c.threshold_retain, r.val_verdict_accuracy_retained);
}

// Options whose parsed value needs a step before it lands in TrainConfig.
struct TrainCommandLine {
  introspection::TrainConfig config;
  std::string optimizer = introspection::optimizer_name(config.optimizer);
  double learning_rate = 0, weight_decay = 0;
  CLI::Option* learning_rate_option = nullptr;
  CLI::Option* weight_decay_option = nullptr;
  bool no_augment = false;
  bool calibrate_only = false;
};

void add_data_options(CLI::App& app, introspection::TrainConfig& c) {
  app.add_option("--dataset", c.dataset, "dataset folder (ivoa-dataset build)")
      ->required()
      ->check(ivoa::input_folder());
  app.add_option("--split", c.split_file, "split file (YAML: train/val/test -> sessions)")
      ->required()
      ->check(ivoa::input_file());
  app.add_option("--out", c.output, "model file to write")->required();
  app.add_option("--train-split", c.train_split, "split file entry whose sessions are trained on")
      ->capture_default_str();
  app.add_option("--val-split", c.val_split, "split file entry that validates (and calibrates the uncertainty gate)")
      ->capture_default_str();
}

void add_optimiser_options(CLI::App& app, TrainCommandLine& cl) {
  auto& c = cl.config;
  app.add_option("--steps", c.steps, "optimiser steps")->capture_default_str()->check(ivoa::positive_number());
  // Bounds for the numbers below: past them LibTorch fails far into the run
  // (bad_alloc, a float overflow naming no flag, a divergence blamed on --lr).
  // 1024 two-view patches take 1.8 GB in a step; 65536 were killed for memory at 24 GB without a word.
  app.add_option("--batch-size", c.batch_size, "patches per step, drawn class-balanced (at most 4096: 1.8 GB a 1024)")
      ->capture_default_str()
      ->check(ivoa::number_in(1, 4096));
  app.add_option("--optimizer", cl.optimizer, "adamw or sgd (the paper's)")
      ->check(CLI::IsMember({"adamw", "sgd"}))
      ->capture_default_str();
  cl.learning_rate_option =
      app.add_option("--lr", cl.learning_rate,
                     fmt::format("learning rate (default: AdamW {}, SGD {}, the paper's)",
                                 introspection::kAdamWLearningRate, introspection::kSgdLearningRate))
          ->check(ivoa::number_in(1e-9, 10));
  app.add_option("--momentum", c.momentum, "SGD momentum (paper: 0.9)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, 1.0));
  cl.weight_decay_option = app.add_option("--weight-decay", cl.weight_decay,
                                          fmt::format("weight decay (default: AdamW {}, decoupled; SGD {}, as L2)",
                                                      introspection::kAdamWWeightDecay, introspection::kSgdWeightDecay))
                               ->check(ivoa::number_in(0, 10));
  app.add_option("--warmup-steps", c.warmup_steps, "linear warm-up, then cosine decay")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
}

void add_model_options(CLI::App& app, TrainCommandLine& cl) {
  auto& c = cl.config;
  app.add_option("--architecture", c.architecture, "slidenet (fast, default) or alexnet (reference, 224x224)")
      ->capture_default_str()
      ->check(CLI::IsMember({"slidenet", "alexnet"}));
  app.add_option("--init", c.init, "start from this model (fine-tuning)")->check(ivoa::input_file());
  app.add_flag("--resume", c.resume, "continue from OUT.checkpoint.* if present");
  app.add_option("--dropout", c.dropout, "dropout before FC1 and FC2 (> 0: the MC-dropout passes need it)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.01, 0.99));
  app.add_option("--fn-weight", c.fn_weight, "FN share of class-balanced sampling (reference: 0.1 outdoors)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--evidence-weight", c.evidence_weight,
                 "weight of the side task: regress the detector's evidence stored with each sample (JPP-C's window "
                 "costs) from the trunk's features; 0: off")
      ->check(ivoa::number_in(0, 1000))
      ->capture_default_str();
  app.add_flag("--no-augment", cl.no_augment, "no photometric augmentation");
  app.add_option("--augment-noise", c.augment_noise_max,
                 "largest per-pixel Gaussian noise sigma the augmentation adds (on [0, 1]; 0: none)")
      ->capture_default_str()
      ->check(ivoa::number_in(0, 1));  // a sigma past the whole range leaves nothing of the patch
  app.add_option("--seed", c.seed, "initial weights, batch draws, augmentation and dropout")
      ->capture_default_str()
      ->check(ivoa::seed_number());
  app.add_option("--threads", c.threads, "LibTorch threads")->capture_default_str()->check(ivoa::positive_number());
  app.add_option("--device", c.device, "cpu or cuda")->capture_default_str()->check(CLI::IsMember({"cpu", "cuda"}));
}

void add_validation_options(CLI::App& app, TrainCommandLine& cl) {
  auto& c = cl.config;
  app.add_option("--validate-every", c.validate_every, "steps between validations (and at the last step)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--checkpoint-every", c.checkpoint_every, "steps between checkpoints that --resume continues from")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_flag("--keep-last", c.keep_last,
               "write the final step's model, not the best-validated one (a few validation sessions make the best "
               "step partly chance)");
  app.add_option("--max-val-samples", c.max_val_samples,
                 "validate on at most this many samples, spread over the sessions")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--threshold-retain", c.threshold_retain,
                 "the stored uncertainty gate keeps this fraction of validation samples")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, 1.0));
  app.add_flag("--calibrate-only", cl.calibrate_only,
               "no training: re-calibrate the uncertainty gates of the --init model on the validation split and "
               "write it to --out");
}

// After parsing: the optimiser's defaults first, then what was given explicitly.
void finish_config(TrainCommandLine& cl) {
  auto& c = cl.config;
  c.augment = !cl.no_augment;
  introspection::use_optimizer(
      c, cl.optimizer == "sgd" ? introspection::Optimizer::kSgd : introspection::Optimizer::kAdamW);
  if (cl.learning_rate_option->count()) c.learning_rate = cl.learning_rate;
  if (cl.weight_decay_option->count()) c.weight_decay = cl.weight_decay;
  if (!cl.calibrate_only && c.warmup_steps > c.steps)
    spdlog::warn(
        "--warmup-steps {} is more than --steps {}: the whole run warms up, to a learning rate of {:.3g} "
        "at its last step instead of --lr {:.3g} (give fewer --warmup-steps)",
        c.warmup_steps, c.steps, c.learning_rate * static_cast<double>(c.steps) / c.warmup_steps, c.learning_rate);
}

int calibrate(const introspection::TrainConfig& c) {
  const auto r = introspection::calibrate_model(c);
  std::printf("model: %s (weights of %s, gates calibrated on %lld validation samples in %.0f s)\n", c.output.c_str(),
              c.init.c_str(), static_cast<long long>(r.val_samples), r.seconds);
  print_gates(r, c);
  return kExitOk;
}

std::string status_line(const introspection::TrainStatus& s) {
  char detail[240], evidence[40] = "";
  if (s.evidence_loss >= 0) std::snprintf(evidence, sizeof(evidence), " (evidence %.4f)", s.evidence_loss);
  std::snprintf(detail, sizeof(detail), "loss %.3f%s, train acc %.3f, lr %.3g, %.0f patches/s, val mean-class acc %s",
                s.loss, evidence, s.accuracy, s.learning_rate, s.patches_per_s,
                s.val_mean_class_accuracy < 0 ? "-" : std::to_string(s.val_mean_class_accuracy).substr(0, 5).c_str());
  return detail;
}

void print_training_report(const introspection::TrainReport& r, const introspection::TrainConfig& c) {
  std::printf("model: %s\n", c.output.c_str());
  if (r.best_before_resume)
    std::printf("best validation (step %lld, before the resume; not beaten since): mean per-class accuracy %.3f\n",
                static_cast<long long>(r.best_step), r.best_val_mean_class_accuracy);
  else
    std::printf(
        "%s (step %lld): mean per-class accuracy %.3f, overall %.3f, per class TP %.3f TN %.3f "
        "FP %.3f FN %.3f\n",
        c.keep_last ? "validation of the final model" : "best validation", static_cast<long long>(r.best_step),
        r.best_val_mean_class_accuracy, r.best_val_accuracy, r.best_val_class_accuracy[0], r.best_val_class_accuracy[1],
        r.best_val_class_accuracy[2], r.best_val_class_accuracy[3]);
  print_gates(r, c);
  std::printf(
      "training: %lld steps (%s, lr %g, weight decay %g) in %.0f s, %.0f patches/s; train samples TP %lld TN "
      "%lld FP %lld FN %lld\n",
      static_cast<long long>(r.last.step), introspection::optimizer_name(c.optimizer), c.learning_rate, c.weight_decay,
      r.seconds, r.last.patches_per_s, static_cast<long long>(r.train_class_counts[0]),
      static_cast<long long>(r.train_class_counts[1]), static_cast<long long>(r.train_class_counts[2]),
      static_cast<long long>(r.train_class_counts[3]));
}

int train(const introspection::TrainConfig& c) {
  Progress progress("training", static_cast<double>(c.steps), "steps", 10.0);
  const auto r = introspection::train_model(
      c, [&](const introspection::TrainStatus& s) { progress.update(static_cast<double>(s.step), status_line(s)); });
  progress.finish();
  print_training_report(r, c);
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  ivoa::introspection::tune_libtorch_runtime(argv);
  CLI::App app{"Train an introspection model on a dataset, validating on held-out sessions"};
  CommonOptions common;
  add_offline_options(app, common);
  TrainCommandLine cl;
  add_data_options(app, cl.config);
  add_model_options(app, cl);
  add_optimiser_options(app, cl);
  add_validation_options(app, cl);
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  finish_config(cl);
  init_logging("train", common.log_level);
  if (cl.calibrate_only && cl.config.init.empty()) {  // a flag error, not bad input (exit 3)
    spdlog::error("--calibrate-only needs --init MODEL: the model whose gates to calibrate");
    return kExitUsage;
  }
  try {
    return cl.calibrate_only ? calibrate(cl.config) : train(cl.config);
  } catch (const introspection::TrainOutputError& e) {
    spdlog::error("{}", e.what());
    return kExitIoError;
  } catch (const std::invalid_argument& e) {  // settings that cannot train, e.g. validating on the training split
    spdlog::error("{}", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {  // ModelError and the rest: the message names the file and what is wrong
    spdlog::error("{}", e.what());
    return kExitBadInput;
  }
}
