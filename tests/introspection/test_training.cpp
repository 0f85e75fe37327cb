// Training mechanics on a small synthetic dataset whose four classes look
// different (synthetic_sessions.hpp): the loss falls and held-out sessions
// are classified far above chance. (Training on simulated sessions is
// tested end to end elsewhere.)
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include <gtest/gtest.h>

#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/introspection/model.hpp"
#include "ivoa/introspection/training.hpp"
#include "file_size_limit.hpp"
#include "synthetic_sessions.hpp"
#include "test_rig.hpp"

namespace ivoa::introspection {

// Test names and messages name the optimiser (found by argument lookup).
void PrintTo(Optimizer o, std::ostream* os) { *os << optimizer_name(o); }

namespace {

void write_session(const std::string& root, const std::string& name, int per_class, unsigned seed,
                   int evidence_size = 0) {
  test::SyntheticSession s;
  s.per_class = per_class;
  s.seed = seed;
  s.evidence_size = evidence_size;
  test::write_synthetic_session(root, name, s);
}

// The tests that hold for either optimiser.
class TrainingWith : public ::testing::TestWithParam<Optimizer> {};

TEST_P(TrainingWith, LossFallsAndHeldOutSessionsBeatChance) {
  test::TempDir dir;
  const std::string root = dir.file("data");
  write_session(root, "a", 60, 1);
  write_session(root, "b", 60, 2);
  write_session(root, "v", 25, 3);
  write_session(root, "held_out", 25, 4);
  std::ofstream(dir.file("split.yaml")) << "train: [a, b]\nval: [v]\ntest: [held_out]\n";

  TrainConfig c;
  c.dataset = root;
  c.split_file = dir.file("split.yaml");
  c.output = dir.file("model.pt");
  c.steps = 150;
  c.batch_size = 32;
  c.warmup_steps = 20;
  c.validate_every = 50;
  c.checkpoint_every = 100;
  c.threshold_passes = 5;
  c.threads = 1;  // ctest -j2 runs the two optimisers' cases side by side: 2 x 2 threads on 2 cores ran 4x slower
  use_optimizer(c, GetParam());
  std::vector<double> losses;
  const TrainReport r = train_model(c, [&](const TrainStatus& s) { losses.push_back(s.loss); });
  ASSERT_EQ(losses.size(), 150u);
  EXPECT_LT(losses.back(), 0.6 * losses[9]);  // running loss after 10 steps vs at the end
  EXPECT_GT(r.best_val_mean_class_accuracy, 0.6);
  EXPECT_GT(r.uncertainty_threshold, 0.0);
  EXPECT_EQ(r.train_class_counts[2], 120);

  // The written model, on the session it never saw.
  InferenceConfig ic;
  ic.mc_passes = 1;
  const auto model = IntrospectionModel::load(c.output, ic);
  EXPECT_NEAR(model->info().uncertainty_threshold, r.uncertainty_threshold, 1e-9);
  EXPECT_GT(r.verdict_uncertainty_threshold, 0.0);
  EXPECT_NEAR(model->info().verdict_uncertainty_threshold, r.verdict_uncertainty_threshold, 1e-9);
  EXPECT_GE(r.val_verdict_accuracy_retained, r.val_accuracy_retained - 1e-9) << "the verdict leaves fewer ways to err";
  EXPECT_EQ(model->info().training_summary.find("held_out"), std::string::npos) << "test sessions must not be listed";
  EXPECT_NE(model->info().training_summary.find("\"a\""), std::string::npos);
  EXPECT_NE(model->info().training_summary.find("\"steps_planned\": 150, \"kept\": \"best_validated\""),
            std::string::npos)
      << model->info().training_summary;
  EXPECT_NE(model->info().training_summary.find("\"augment_noise_max\": 0.03"), std::string::npos)
      << model->info().training_summary;
  EXPECT_NE(model->info().training_summary.find(std::string("\"optimizer\": \"") + optimizer_name(GetParam()) + "\""),
            std::string::npos)
      << model->info().training_summary;
  const dataset::SessionReader test((dir.path() / "data" / "held_out").string());
  std::vector<cv::Mat> patches;
  for (size_t i = 0; i < test.size(); ++i) patches.push_back(test.patch(i).clone());
  const PatchOutputs out = model->run_patches(patches, false);
  int right = 0;
  for (size_t i = 0; i < test.size(); ++i) right += out.predictions[i].predicted == test.samples()[i].label;
  EXPECT_GT(static_cast<double>(right) / static_cast<double>(test.size()), 0.6);  // chance is 0.25
}

// The training summary the model file at `path` carries.
std::string training_summary_of(const std::string& path) {
  InferenceConfig ic;
  ic.mc_passes = 1;
  return IntrospectionModel::load(path, ic)->info().training_summary;
}

// A short training run on dir/data with dir/split.yaml.
TrainConfig tiny_config(const test::TempDir& dir, int64_t steps) {
  TrainConfig c;
  c.dataset = dir.file("data");
  c.split_file = dir.file("split.yaml");
  c.output = dir.file("model.pt");
  c.steps = steps;
  c.batch_size = 8;
  c.warmup_steps = 2;
  c.validate_every = 5;
  c.checkpoint_every = 5;
  c.threshold_passes = 3;
  c.threads = 1;  // beside another test under ctest -j2
  return c;
}

// A train session "a" of 10 samples per class and a validation session "v"
// of `val_per_class`, and a short training run on them.
TrainConfig tiny_run(const test::TempDir& dir, int val_per_class, int64_t steps) {
  write_session(dir.file("data"), "a", 10, 1);
  write_session(dir.file("data"), "v", val_per_class, 3);
  std::ofstream(dir.file("split.yaml")) << "train: [a]\nval: [v]\n";
  return tiny_config(dir, steps);
}

TEST_P(TrainingWith, ResumesFromTheCheckpoint) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 10);
  use_optimizer(c, GetParam());
  const TrainReport before = train_model(c);
  c.steps = 14;
  c.resume = true;
  int64_t first = -1;
  const TrainReport r = train_model(c, [&](const TrainStatus& s) {
    if (first < 0) first = s.step;
  });
  EXPECT_EQ(first, 11);        // continued after step 10, not from scratch
  if (r.best_before_resume) {  // the checkpoint's best stands: its numbers, nothing invented
    EXPECT_EQ(r.best_step, before.best_step);
    EXPECT_NEAR(r.best_val_mean_class_accuracy, before.best_val_mean_class_accuracy, 1e-5);
  } else {
    EXPECT_GT(r.best_step, 10);
    EXPECT_GT(r.best_val_accuracy, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Optimizers, TrainingWith, ::testing::Values(Optimizer::kSgd, Optimizer::kAdamW),
                         [](const ::testing::TestParamInfo<Optimizer>& p) { return optimizer_name(p.param); });

// --out is written once, calibrated, at the end: a run stopped part way
// (Ctrl-C, a kill, a full disk) leaves the model an earlier run wrote there
// as it was; it used to be replaced by each better validated model, its
// gates not yet calibrated.
TEST(Training, ARunStoppedPartWayLeavesTheEarlierModelAsItWas) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 20);
  std::ofstream(c.output) << "an earlier run's model";
  struct Stopped {};
  try {
    train_model(c, [&](const TrainStatus& s) {
      if (s.step == 12) throw Stopped{};  // after two validations
    });
    FAIL() << "not stopped";
  } catch (const Stopped&) {
  }
  std::ifstream in(c.output);
  const std::string kept((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(kept, "an earlier run's model");
  EXPECT_TRUE(std::filesystem::exists(c.output + ".checkpoint.kept"));
  c.resume = true;  // and the resumed run writes the model it kept, calibrated
  const TrainReport r = train_model(c);
  EXPECT_GT(r.val_accuracy_retained, 0);
  const std::string summary = training_summary_of(c.output);
  EXPECT_EQ(summary.find("\"val_accuracy_retained\": 0,"), std::string::npos) << summary;
}

// A resumed run keeps the settings and sessions it started with (its model
// would say it trained all its steps with the new ones); more steps are fine.
TEST(Training, ResumingWithOtherSettingsIsRefusedNamingThem) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 10);
  train_model(c);
  c.resume = true;
  c.steps = 12;
  c.batch_size = 16;
  c.augment = false;
  try {
    train_model(c);
    FAIL() << "resumed with other settings";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("other settings than these: batch_size 16 (was 8), augment off"),
              std::string::npos)
        << e.what();
  }
  c.batch_size = 8;
  c.augment = true;
  EXPECT_EQ(train_model(c).last.step, 12);
}

TEST(Training, KeepLastWritesTheFinalStepsModelWhateverItsValidation) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 20);
  c.keep_last = true;
  double final_validation = -1;
  bool written_early = false;
  const TrainReport r = train_model(c, [&](const TrainStatus& s) {
    if (s.step < c.steps) written_early = written_early || std::filesystem::exists(c.output);
    if (s.step == c.steps) final_validation = s.val_mean_class_accuracy;
  });
  EXPECT_FALSE(written_early);
  EXPECT_EQ(r.best_step, 20);
  EXPECT_FALSE(r.best_before_resume);
  EXPECT_NEAR(r.best_val_mean_class_accuracy, final_validation, 1e-9);
  const std::string summary = training_summary_of(c.output);
  EXPECT_NE(summary.find("\"best_step\": 20"), std::string::npos) << summary;
}

// The summary names the data by absolute path, quoted: a folder whose name
// held a '"' wrote a model that no program could read.
TEST(Training, TheModelNamesItsDataWhateverTheFolderIsCalled) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);
  std::filesystem::rename(dir.file("data"), dir.file("my \"best\" data"));
  c.dataset = dir.file("my \"best\" data");
  train_model(c);
  const std::string summary = training_summary_of(c.output);
  EXPECT_NE(summary.find(R"("dataset": ")" + dir.path().string() + R"(/my \"best\" data")"), std::string::npos)
      << summary;
}

// The model records the image sizes of the sessions it was trained on (not
// those it was validated on), so the tools can say when it meets another
// camera; one session that does not say leaves none recorded.
TEST(Training, TheModelRecordsTheImageSizesItWasTrainedOn) {
  const auto sizes_trained_on = [](const std::vector<cv::Size>& train_sizes) {
    test::TempDir dir;
    std::string names;
    for (size_t k = 0; k < train_sizes.size(); ++k) {
      test::SyntheticSession s;
      s.seed = static_cast<unsigned>(k + 1);
      s.image_size = train_sizes[k];
      test::write_synthetic_session(dir.file("data"), "t" + std::to_string(k), s);
      names += (k ? ", t" : "t") + std::to_string(k);
    }
    test::SyntheticSession v;
    v.per_class = 5;
    v.seed = 9;
    v.image_size = {1280, 720};
    test::write_synthetic_session(dir.file("data"), "v", v);
    std::ofstream(dir.file("split.yaml")) << "train: [" << names << "]\nval: [v]\n";
    train_model(tiny_config(dir, 5));
    InferenceConfig ic;
    ic.mc_passes = 2;
    return IntrospectionModel::load(dir.file("model.pt"), ic)->info().image_sizes;
  };
  using Sizes = std::vector<cv::Size>;
  EXPECT_EQ(sizes_trained_on({{960, 600}, {960, 600}}), Sizes{cv::Size(960, 600)});
  EXPECT_EQ(sizes_trained_on({{960, 600}, {640, 480}}), (Sizes{{960, 600}, {640, 480}}));
  EXPECT_EQ(sizes_trained_on({{960, 600}, {}}), Sizes{});
}

// A loss that is no number would leave NaN weights and gates, reported as a success.
TEST(Training, ADivergedTrainingStopsAndSaysSo) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 30);
  c.learning_rate = 1e12;
  try {
    train_model(c);
    FAIL() << "trained at lr 1e12 without a word";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("training diverged (try a lower --lr"), std::string::npos) << e.what();
  }
}

// Weights that are finite but overflow on real input: the first validation
// used to keep (and save) a model that predicts only NaN.
TEST(Training, AModelWhoseValidationOutputsAreNotNumbersIsNotKept) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 3);
  c.validate_every = 1;
  c.learning_rate = 1e30;
  try {
    train_model(c);
    FAIL() << "trained at lr 1e30 without a word";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("step 1: the model's outputs on the validation patches are not numbers"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("no model was written"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(c.output));
}

// A validation of one sample scores 0 or 1: a run must leave a model either way.
TEST(Training, AValidationThatScoresNothingStillLeavesAModel) {
  for (const uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) {
    test::TempDir dir;
    TrainConfig c = tiny_run(dir, 5, 1);
    c.max_val_samples = 1;
    c.seed = seed;
    const TrainReport r = train_model(c);
    EXPECT_EQ(r.best_step, 1) << "seed " << seed;
    EXPECT_TRUE(std::filesystem::exists(c.output)) << "seed " << seed;
  }
}

// Why resuming `c` from its checkpoint, to `steps`, was refused; "" if it resumed.
std::string resume_refusal(TrainConfig c, int64_t steps) {
  c.resume = true;
  c.steps = steps;
  try {
    train_model(c);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(Training, StaleCheckpointIsRefusedWithTheWayOut) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);  // a checkpoint at step 5
  train_model(c);
  c.architecture = "alexnet";  // another setup in the same --out
  const std::string what = resume_refusal(c, c.steps);
  ASSERT_FALSE(what.empty()) << "resumed from a checkpoint of another architecture";
  EXPECT_NE(what.find("cannot resume"), std::string::npos) << what;
  EXPECT_NE(what.find("architecture slidenet, not alexnet"), std::string::npos) << what;
  EXPECT_NE(what.find(c.output + ".checkpoint.*"), std::string::npos) << what;
}

TEST(Training, CheckpointOfAnotherOptimiserIsRefusedWithTheWayOut) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);  // an SGD checkpoint at step 5
  use_optimizer(c, Optimizer::kSgd);
  train_model(c);
  use_optimizer(c, Optimizer::kAdamW);
  const std::string what = resume_refusal(c, 8);
  ASSERT_FALSE(what.empty()) << "resumed AdamW from SGD's optimiser state";
  EXPECT_NE(what.find("trained with --optimizer sgd, this run uses adamw"), std::string::npos) << what;
  EXPECT_NE(what.find(c.output + ".checkpoint.*"), std::string::npos) << what;
}

TEST(Training, DamagedCheckpointStepFileIsRefusedWithTheWayOut) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);  // a checkpoint at step 5
  train_model(c);
  std::ofstream(c.output + ".checkpoint.step") << "5 0.";  // cut short, as by a full disk
  const std::string what = resume_refusal(c, 8);
  ASSERT_FALSE(what.empty()) << "resumed from a step file that does not say where it stopped";
  EXPECT_NE(what.find(c.output + ".checkpoint.step is not"), std::string::npos) << what;
  EXPECT_NE(what.find(c.output + ".checkpoint.*"), std::string::npos) << what;
}

// LibTorch does not check a checkpoint's CRCs: a damaged optimiser state
// loaded, trained to NaN and replaced the good model and checkpoint.
TEST(Training, ADamagedOptimiserCheckpointIsRefusedAndTheModelKept) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);  // a checkpoint at step 5
  train_model(c);
  const std::string model = test::read_file(c.output);
  // A byte in the middle of the archive's first entry (a stored tensor,
  // uncompressed): its size and place are in the zip's central directory.
  // The middle of the file could land in a header's padding, which no CRC
  // covers (the test failed once so).
  const std::string path = c.output + ".checkpoint.optimizer";
  const std::string bytes = test::read_file(path);
  const auto u16 = [&](size_t at) {
    return static_cast<uint8_t>(bytes[at]) | static_cast<uint8_t>(bytes[at + 1]) << 8;
  };
  const auto u32 = [&](size_t at) { return static_cast<uint32_t>(u16(at)) | static_cast<uint32_t>(u16(at + 2)) << 16; };
  ASSERT_GT(bytes.size(), 22u);
  const size_t end_record = bytes.size() - 22;  // no archive comment
  ASSERT_EQ(bytes.compare(end_record, 4, "PK\x05\x06"), 0) << "not a zip archive without a comment";
  const size_t entry = u32(end_record + 16);  // the central directory's first entry
  ASSERT_EQ(bytes.compare(entry, 4, "PK\x01\x02"), 0);
  const size_t size = u32(entry + 20), local = u32(entry + 42);
  const size_t data = local + 30 + u16(local + 26) + u16(local + 28);
  ASSERT_GT(size, 0u);
  ASSERT_LE(data + size, bytes.size());
  std::fstream optimiser(path, std::ios::in | std::ios::out | std::ios::binary);
  optimiser.seekp(static_cast<std::streamoff>(data + size / 2));
  optimiser.put(static_cast<char>(bytes[data + size / 2] ^ 0x5a));
  optimiser.close();
  const std::string what = resume_refusal(c, 8);
  ASSERT_FALSE(what.empty()) << "resumed from a damaged optimiser state";
  EXPECT_NE(what.find("cannot resume " + c.output + ".checkpoint: " + c.output + ".checkpoint.optimizer: "),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("the model file is damaged"), std::string::npos) << what;
  EXPECT_EQ(test::read_file(c.output), model);
}

// --out that is an input, or a device: it used to be replaced (as root,
// /dev/full became a model file).
TEST(Training, AnOutputThatIsAnInputOrNotAFileIsRefused) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 1);
  const std::string split = test::read_file(c.split_file);
  const auto refusal = [&](const std::string& out) {
    TrainConfig bad = c;
    bad.output = out;
    try {
      train_model(bad);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("trained");
  };
  EXPECT_EQ(refusal(c.split_file), "--out " + c.split_file + " is the split file: it would be written over");
  EXPECT_EQ(refusal(dir.file("data/a/patches.bin")), "--out " + dir.file("data/a/patches.bin") +
                                                         " is a file of the dataset " + c.dataset +
                                                         ": it would be written over");
  EXPECT_EQ(refusal(dir.file("data")),
            "--out " + dir.file("data") + " exists and is not a file (a device, folder or pipe)");
  EXPECT_EQ(test::read_file(c.split_file), split);
  std::ofstream(dir.file("start.pt")) << "the model fine-tuned from";
  c.init = dir.file("start.pt");
  EXPECT_EQ(refusal(dir.file("./start.pt")),
            "--out " + dir.file("./start.pt") + " is the --init model: it would be written over");
  EXPECT_EQ(test::read_file(dir.file("start.pt")), "the model fine-tuned from");
}

TEST(Training, ADiskThatFillsDuringACheckpointKeepsTheLastOneForResume) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);  // a checkpoint at step 5
  train_model(c);
  const std::string checkpoint = c.output + ".checkpoint";
  std::map<std::string, std::string> before;
  for (const char* part : {".model", ".optimizer", ".step"}) before[part] = test::read_file(checkpoint + part);
  c.resume = true;
  c.steps = 10;
  try {
    // Room for the model (the best so far, and the checkpoint's), not for the optimiser's state (AdamW: twice it).
    const test::FileSizeLimit nearly_full_disk(before[".model"].size() + 1000);
    train_model(c);
    FAIL() << "the checkpoint at step 10 could not be written, and nobody was told";
  } catch (const TrainOutputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(checkpoint + ".optimizer: cannot write"), std::string::npos) << what;
    EXPECT_NE(what.find("the previous file, if any, is kept"), std::string::npos) << what;
  }
  for (const auto& [part, bytes] : before) EXPECT_EQ(test::read_file(checkpoint + part), bytes) << part;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
  int64_t first = -1;
  train_model(c, [&](const TrainStatus& s) {
    if (first < 0) first = s.step;
  });
  EXPECT_EQ(first, 6);  // resumed from the step-5 checkpoint kept whole
}

TEST(Training, AnOptimiserStateCutShortIsRefusedWithTheWayOut) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 5, 5);
  train_model(c);
  const std::string optimizer = c.output + ".checkpoint.optimizer";
  const std::string bytes = test::read_file(optimizer);
  std::ofstream(optimizer, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  const std::string what = resume_refusal(c, 8);
  ASSERT_FALSE(what.empty()) << "resumed from half an optimiser state";
  EXPECT_NE(what.find("cannot resume " + c.output + ".checkpoint: its optimiser or side-task state cannot be read"),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("remove " + c.output + ".checkpoint.* to start over"), std::string::npos) << what;
  EXPECT_EQ(what.find("frame #"), std::string::npos) << "LibTorch's backtrace: " << what;
}

TEST(Training, LearnsTheDetectorsEvidenceAsASideTaskWhenTheDatasetHasIt) {
  test::TempDir dir;
  const std::string root = dir.file("data");
  write_session(root, "a", 20, 1, 5);
  write_session(root, "v", 5, 3, 5);
  write_session(root, "plain", 20, 2);  // built without evidence
  std::ofstream(dir.file("split.yaml")) << "train: [a]\nval: [v]\n";
  std::ofstream(dir.file("mixed.yaml")) << "train: [a, plain]\nval: [v]\n";
  TrainConfig c = tiny_config(dir, 60);
  c.validate_every = c.checkpoint_every = 30;
  std::vector<double> evidence_losses;
  train_model(c, [&](const TrainStatus& s) { evidence_losses.push_back(s.evidence_loss); });
  ASSERT_EQ(evidence_losses.size(), 60u);
  EXPECT_GT(evidence_losses.front(), 0.0);
  EXPECT_LT(evidence_losses.back(), 0.5 * evidence_losses[4]) << "the head learns what the class implies";
  const std::string summary = training_summary_of(c.output);
  EXPECT_NE(summary.find("\"evidence_weight\": 5"), std::string::npos) << summary;

  // Resuming must keep the setting the checkpoint was trained with.
  c.resume = true;
  c.steps = 65;
  c.evidence_weight = 0;
  try {
    train_model(c);
    FAIL() << "resumed without the side task from a checkpoint trained with it";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("with the evidence side task, this run without"), std::string::npos)
        << e.what();
  }

  // Off, or sessions without evidence among the training ones: no side task.
  for (const auto& [split, weight] : {std::pair{dir.file("split.yaml"), 0.0}, {dir.file("mixed.yaml"), 5.0}}) {
    TrainConfig off = c;
    off.resume = false;
    off.split_file = split;
    off.evidence_weight = weight;
    off.output = dir.file("off.pt");
    off.steps = 5;
    double last = 0;
    train_model(off, [&](const TrainStatus& s) { last = s.evidence_loss; });
    EXPECT_EQ(last, -1.0) << split;
  }
}

TEST(Training, CalibrationOnlyRewritesTheGatesNotTheWeights) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 20, 20);
  train_model(c);
  c.init = c.output;
  c.output = dir.file("recalibrated.pt");
  c.threshold_retain = 0.5;  // a stricter gate
  const TrainReport r = calibrate_model(c);
  EXPECT_EQ(r.val_samples, 80);
  InferenceConfig ic;
  ic.mc_passes = 1;
  const auto before = IntrospectionModel::load(c.init, ic), after = IntrospectionModel::load(c.output, ic);
  EXPECT_NEAR(after->info().uncertainty_threshold, r.uncertainty_threshold, 1e-9);
  EXPECT_NEAR(after->info().verdict_uncertainty_threshold, r.verdict_uncertainty_threshold, 1e-9);
  EXPECT_LE(r.uncertainty_threshold, before->info().uncertainty_threshold);  // 50 % retained instead of 70 %
  EXPECT_EQ(after->info().training_summary, before->info().training_summary);
  const dataset::SessionReader val((dir.path() / "data" / "v").string());
  const auto a = before->run_patches({val.patch(0).clone()}, false).predictions[0];
  const auto b = after->run_patches({val.patch(0).clone()}, false).predictions[0];
  for (size_t k = 0; k < 4; ++k) EXPECT_EQ(a.probability[k], b.probability[k]);
  c.init.clear();
  EXPECT_THROW(calibrate_model(c), std::runtime_error);
}

// The cells of a validation batch share their dropout masks, so a gate
// calibrated from one batch followed its one draw (seeds gave gates up to
// 4.6x apart); draws are now pooled until there are enough.
TEST(Training, TheGateDoesNotHangOnOneDropoutDraw) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 20, 20);
  train_model(c);
  c.init = c.output;
  double lowest = 1e9, highest = 0;
  for (const uint64_t seed : {1, 2, 3, 4, 5}) {
    c.seed = seed;
    c.output = dir.file("seed" + std::to_string(seed) + ".pt");
    const double gate = calibrate_model(c).uncertainty_threshold;
    lowest = std::min(lowest, gate), highest = std::max(highest, gate);
  }
  EXPECT_GT(lowest, 0);
  EXPECT_LT(highest / lowest, 1.5) << lowest << " .. " << highest;
}

// What train_model refuses `split_yaml` with, over the sessions "a" and
// "b" (two samples a class), "empty" (none) and "dense" (two samples a
// class, the dense detector's labels); "accepted" if it trains.
std::string refusal_of_split(test::TempDir& dir, const std::string& split_yaml) {
  write_session(dir.file("data"), "a", 2, 1);
  write_session(dir.file("data"), "b", 2, 2);
  write_session(dir.file("data"), "empty", 0, 3);
  test::SyntheticSession dense;
  dense.per_class = 2;
  dense.detector = "dense";
  test::write_synthetic_session(dir.file("data"), "dense", dense);
  std::ofstream(dir.file("split.yaml")) << split_yaml;
  TrainConfig c;
  c.dataset = dir.file("data");
  c.split_file = dir.file("split.yaml");
  c.output = dir.file("m.pt");
  c.steps = 2;
  c.threads = 1;
  try {
    train_model(c);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Training, MissingSplitIsNamed) {
  test::TempDir dir;
  const std::string why = refusal_of_split(dir, "train: [a]\n");
  EXPECT_NE(why.find("'val'"), std::string::npos) << why;
}

// A validation split whose sessions have no labels would give no model to
// keep and no gate: refused before any training step, naming the sessions.
TEST(Training, ValidationSessionsWithoutSamplesAreNamedBeforeTraining) {
  test::TempDir dir;
  const std::string why = refusal_of_split(dir, "train: [a]\nval: [empty]\n");
  EXPECT_NE(why.find("\"empty\""), std::string::npos) << why;
  EXPECT_NE(why.find("no labelled samples"), std::string::npos) << why;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.pt")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.pt.checkpoint.step")));
  test::TempDir control;
  EXPECT_EQ(refusal_of_split(control, "train: [a]\nval: [b]\n"), "accepted");
}

// A model introspects one detector: labels of two are not mixed.
TEST(Training, SessionsLabelledFromAnotherDetectorAreRefused) {
  test::TempDir dir;
  std::string why = refusal_of_split(dir, "train: [a, dense]\nval: [b]\n");
  EXPECT_NE(why.find("dense: labelled from the 'dense' detector, the other sessions from 'jppc'"), std::string::npos)
      << why;
  test::TempDir other;
  why = refusal_of_split(other, "train: [a]\nval: [dense]\n");
  EXPECT_NE(why.find("validation sessions are labelled from the 'dense' detector"), std::string::npos) << why;
}

// The model's folder is made if need be; one that cannot be made is an
// output error before any step, not a LibTorch backtrace after the first.
TEST(Training, MakesTheModelsFolderOrSaysItCannot) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 2, 2);
  c.output = dir.file("models/today/m.pt");
  train_model(c);
  EXPECT_TRUE(std::filesystem::exists(c.output));

  c.output = dir.file("split.yaml/m.pt");  // a file where the folder should be
  try {
    train_model(c);
    FAIL();
  } catch (const TrainOutputError& e) {
    EXPECT_NE(std::string(e.what()).find("split.yaml/m.pt: cannot create its folder"), std::string::npos) << e.what();
  }

  c.output = "/proc/m.pt";  // a folder no file can be made in: said before the training, not after
  bool trained = false;
  try {
    train_model(c, [&](const TrainStatus&) { trained = true; });
    FAIL();
  } catch (const TrainOutputError& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/m.pt: cannot write there"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(trained);
  EXPECT_FALSE(std::filesystem::exists(dir.file("models/today/m.pt.writable")));
}

// Validating on the training split would keep the model that fits it best
// and calibrate the gate on seen samples: refused before anything is written.
TEST(Training, ValidationOnTheTrainingSplitIsRefused) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 2, 2);
  c.val_split = c.train_split;
  try {
    train_model(c);
    FAIL() << "validated on the training split";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the validation split 'train' is the one trained on"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(c.output));
}

// A device this LibTorch cannot use is refused before any step, and
// without writing anything (cuda used to end in LibTorch's backtrace; any
// other name trained on the CPU). Debian's LibTorch has no CUDA.
TEST(Training, DeviceItCannotUseIsRefusedByName) {
  test::TempDir dir;
  TrainConfig c = tiny_run(dir, 2, 2);
  for (const auto& [device, why] :
       {std::pair<std::string, std::string>{"cuda", "no usable CUDA"}, {"gpu", "unknown device 'gpu' (cpu, cuda)"}}) {
    c.device = device;
    try {
      train_model(c);
      FAIL() << "trained on device '" << device << "'";
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(c.output)) << device;
  }
}

}  // namespace
}  // namespace ivoa::introspection
