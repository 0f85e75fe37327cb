// ivoa-eval as a user runs it, on a small synthetic dataset and a model
// trained on it for a few steps: what it writes, what it warns about, what
// it refuses and with which exit code.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/introspection/training.hpp"
#include "ivoa/logio/log_writer.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"
#include "model_file.hpp"
#include "synthetic_sessions.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

constexpr int kPerClass = 3;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

size_t count_lines(const std::string& text) {
  size_t n = 0;
  for (const char c : text) n += c == '\n';
  return n;
}

// A JPP-C model, and sessions beside its training ones: "t" (test split,
// JPP-C's labels), "d" (split "dense": the dense detector's labels) and
// "s" (split "scaled": footprint-scaled patches the model never saw).
class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    test::SyntheticSession s;
    s.per_class = kPerClass;
    s.scene = "office";
    s.scene_seed = 31;
    s.image_size = {960, 600};
    for (const char* name : {"a", "v", "t"}) {
      test::write_synthetic_session(dir_.file("data"), name, s);
      ++s.seed;
    }
    s.image_size = {640, 480};
    test::write_synthetic_session(dir_.file("data"), "c", s);
    s.image_size = {960, 600};
    s.detector = "dense";
    test::write_synthetic_session(dir_.file("data"), "d", s);
    s.detector = "jppc";
    s.patch_scale = 1.6;
    test::write_synthetic_session(dir_.file("data"), "s", s);
    s.views = 2;
    test::write_synthetic_session(dir_.file("data"), "b", s);
    s.views = 1;
    s.patch_scale = 0;
    s.patch_size = 64;
    test::write_synthetic_session(dir_.file("data"), "q", s);
    s.per_class = 0;
    test::write_synthetic_session(dir_.file("data"), "z", s);           // a session without samples
    std::filesystem::create_directories(dir_.file("data/unfinished"));  // a build that never wrote session.json
    std::ofstream(dir_.file("split.yaml")) << "train: [a]\nval: [v]\ntest: [t]\ndense: [d]\nscaled: [s]\n"
                                              "scaled_two_views: [b]\nempty: []\nunfinished: [unfinished]\n"
                                              "no_samples: [z]\nother_size: [q]\nother_camera: [c]\n";

    introspection::TrainConfig c;
    c.dataset = dir_.file("data");
    c.split_file = dir_.file("split.yaml");
    c.output = dir_.file("model.pt");
    c.steps = 2;
    c.batch_size = 8;
    c.threads = 1;
    introspection::train_model(c);
  }

  test::CommandResult eval(const std::string& splits, const std::string& more = "") const {
    return test::run_command("timeout 120 " IVOA_EVAL_EXE " --model " + dir_.file("model.pt") + " --dataset " +
                             dir_.file("data") + " --split " + dir_.file("split.yaml") + " --out " + out() +
                             " --mc-passes 2 --threads 1 --splits " + splits + " " + more);
  }
  std::string out() const { return dir_.file("eval"); }

  test::TempDir dir_;
};

TEST_F(EvalCli, WritesARowAndAnEmbeddingPerSampleOfTheSplitsAsked) {
  const auto r = eval("test");
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_FALSE(contains(r.output, "warning")) << r.output;
  const std::string csv = test::read_file(out() + "/predictions.csv");
  EXPECT_EQ(count_lines(csv), 1u + 4 * kPerClass) << "a header and a row per sample";
  EXPECT_EQ(csv.rfind("session,environment,split,sample,", 0), 0u);
  EXPECT_EQ(test::read_file(out() + "/embeddings.f32").size(), 4u * kPerClass * 256 * sizeof(float));
  const std::string json = test::read_file(out() + "/eval.json");
  EXPECT_TRUE(contains(
      json, "{\"split\": \"test\", \"session\": \"t\", \"patch_scale\": 0, \"views\": 1, \"image_size\": [960, 600]}"))
      << json;
  EXPECT_TRUE(contains(json, "\"image_sizes\": [[960, 600]]")) << json;
  EXPECT_TRUE(contains(json, "\"dataset\": \"" + dir_.file("data") + "\"")) << json;
  EXPECT_TRUE(contains(json, "\"detector\": \"jppc\"")) << json;
}

TEST_F(EvalCli, WarnsWhenTheSessionsAreLabelledFromAnotherDetector) {
  const auto r = eval("test,dense");
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(contains(r.output, "introspects the 'jppc' detector, but 1 of the 2 sessions")) << r.output;
  EXPECT_TRUE(contains(r.output, "d, from 'dense'")) << r.output;
  EXPECT_EQ(count_lines(test::read_file(out() + "/predictions.csv")), 1u + 8 * kPerClass);
}

// The patches are cut on the ground and resized, so it runs, but the
// figures are of a camera the model has never seen, which the user is told.
TEST_F(EvalCli, WarnsWhenTheSessionsAreOfACameraTheModelWasNotTrainedOn) {
  const auto r = eval("test,other_camera");
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(contains(r.output,
                       "was trained on 960x600 images, but 1 of the 2 sessions is of another size (the first, "
                       "c, 640x480)"))
      << r.output;
  EXPECT_TRUE(contains(test::read_file(out() + "/eval.json"),
                       "\"session\": \"c\", \"patch_scale\": 0, \"views\": 1, "
                       "\"image_size\": [640, 480]"));
}

TEST_F(EvalCli, RefusesPatchesCutUnlikeTheModelsNamingTheSessionAndTheFix) {
  const auto r = eval("scaled");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "session s has patch scale 1.6")) << r.output;
  EXPECT_TRUE(contains(r.output, "--patch-scale 0")) << r.output;
}

TEST_F(EvalCli, NamesEveryWayThePatchesDifferAtOnce) {
  const auto r = eval("scaled_two_views");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "session b has patch scale 1.6 (model: 0), 2 view(s) per patch (model: 1)"))
      << r.output;
  EXPECT_TRUE(contains(r.output, "--patch-scale 0 --views 1")) << r.output;
}

// They would be resized to the model's, as they never were in training.
TEST_F(EvalCli, RefusesPatchesOfAnotherSize) {
  const auto r = eval("other_size");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "session q has 64 px patches (model: 100)")) << r.output;
  EXPECT_TRUE(contains(r.output, "--patch-size 100")) << r.output;
}

// Finite weights that overflow on real input: a diverged training's model
// wrote rows of NaN and exited 0.
TEST_F(EvalCli, RefusesAModelThatPredictsNaN) {
  introspection::NativeModel model = introspection::load_native_model(dir_.file("model.pt"));
  {
    torch::NoGradGuard no_grad;
    for (auto& p : model.net->parameters()) p.mul_(1e30);
  }
  introspection::save_model(*model.net, model.info, dir_.file("model.pt"));
  const auto r = eval("test");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "predicts a probability that is not a number (session t, sample 0)")) << r.output;
}

TEST_F(EvalCli, OverlaysOfAnEarlierRunAreRemovedNotPassedOffAsThisModels) {
  std::filesystem::create_directories(out() + "/overlays");
  std::ofstream(out() + "/overlays/t_1700310000000000.png") << "an earlier model's figure";
  std::ofstream(out() + "/overlays/notes.txt") << "the user's";
  std::ofstream(out() + "/overlays/summary.png") << "the user's too";
  const auto r = eval("test");
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out() + "/overlays/t_1700310000000000.png"));
  EXPECT_TRUE(std::filesystem::exists(out() + "/overlays/notes.txt"));
  EXPECT_TRUE(std::filesystem::exists(out() + "/overlays/summary.png"));
  EXPECT_TRUE(contains(r.output, "removed 1 overlay figures of an earlier run")) << r.output;
}

template <typename Message>
void write_message(logio::LogWriter& log, const char* channel, const Message& m) {
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  log.write(channel, m.utime, bytes.data(), bytes.size());
}

// A simulated log of the synthetic sessions' one frame (utime 0), its
// truth naming `scene` and `seed`.
void write_simulated_log(const std::string& path, const std::string& scene, int64_t seed) {
  logio::LogWriter log(path);
  const cv::Mat image(2 * static_cast<int>(test::kSyntheticCellV), 2 * static_cast<int>(test::kSyntheticCellU), CV_8UC3,
                      cv::Scalar(60, 120, 180));
  stereo_image_t frame{};
  frame.left = frame.right = encode_image(image, image_t::PIXEL_FORMAT_BGR, 0);
  write_message(log, "STEREO_IMAGES", frame);
  sim_ground_truth_t truth{};
  truth.scene = scene;
  truth.seed = seed;
  truth.environment = "indoor";
  write_message(log, "SIM_GROUND_TRUTH", truth);
}

TEST_F(EvalCli, OverlaysComeOnlyFromALogOfTheSessionsSceneAndSeed) {
  std::filesystem::create_directories(dir_.file("own"));
  std::filesystem::create_directories(dir_.file("other"));
  write_simulated_log(dir_.file("own/t.lcmlog"), "office", 31);
  auto r = eval("test", "--logs " + dir_.file("own/t.lcmlog"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out() + "/overlays/t_0.png")) << r.output;

  // Another scene's log under this session's name: its frame times match,
  // so without the check the session's labels would be drawn on it.
  std::filesystem::remove(out() + "/overlays/t_0.png");
  write_simulated_log(dir_.file("other/t.lcmlog"), "lobby", 31);
  r = eval("test", "--logs " + dir_.file("other/t.lcmlog"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out() + "/overlays/t_0.png"));
  EXPECT_TRUE(contains(r.output,
                       "a log of scene lobby seed 31, but session 't' was recorded from scene office seed "
                       "31: no overlays from it"))
      << r.output;
  // The truth comes after the frame's images: a budget full at the first
  // frame must not skip the check.
  r = eval("test", "--max-overlays 1 --logs " + dir_.file("other/t.lcmlog"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out() + "/overlays/t_0.png"));
  EXPECT_TRUE(contains(r.output, "a log of scene lobby seed 31")) << r.output;
}

// A log whose stereo pairs do not decode, or without the session's frames,
// gave fewer overlays (or none) without a word.
TEST_F(EvalCli, StereoPairsThatGiveNoOverlayAreSaid) {
  std::filesystem::create_directories(dir_.file("cut"));
  {
    logio::LogWriter log(dir_.file("cut/t.lcmlog"));
    const uint8_t not_a_pair[12] = {1, 2, 3};
    log.write("STEREO_IMAGES", 0, not_a_pair, sizeof not_a_pair);
  }
  const auto r = eval("test", "--logs " + dir_.file("cut/t.lcmlog"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(contains(r.output, "t.lcmlog: 1 STEREO_IMAGES messages do not decode as stereo pairs")) << r.output;
  EXPECT_TRUE(contains(r.output, "t.lcmlog: none of session t's labelled frames is in it")) << r.output;
}

// A log the logger split (t.lcmlog.00, .01, ...) is the session "t", as
// ivoa-dataset names it.
TEST_F(EvalCli, APartOfASplitLogIsItsSessionsLog) {
  std::filesystem::create_directories(dir_.file("own"));
  write_simulated_log(dir_.file("own/t.lcmlog.00"), "office", 31);
  const auto r = eval("test", "--logs " + dir_.file("own/t.lcmlog.00"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out() + "/overlays/t_0.png")) << r.output;
  EXPECT_FALSE(contains(r.output, "no session")) << r.output;
}

// One overlay every N labelled frames of the session, counted across its
// split parts: the count started again at each part.
TEST_F(EvalCli, OverlaySpacingRunsAcrossASessionsSplitParts) {
  std::filesystem::create_directories(dir_.file("own"));
  write_simulated_log(dir_.file("own/t.lcmlog.00"), "office", 31);
  write_simulated_log(dir_.file("own/t.lcmlog.01"), "office", 31);  // its one labelled frame again
  const auto r =
      eval("test", "--overlay-every 2 --logs " + dir_.file("own/t.lcmlog.00") + " " + dir_.file("own/t.lcmlog.01"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(contains(r.output, "wrote 1 overlay figures")) << r.output;
}

TEST_F(EvalCli, ASplitWithoutSessionsIsBadInput) {
  const auto r = eval("empty");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "split.yaml: the split(s) empty list no session: nothing to evaluate")) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out() + "/eval.json"));
}

TEST_F(EvalCli, SessionsWithoutSamplesAreRefusedBeforeAnEarlierEvalIsTouched) {
  ASSERT_EQ(eval("test").exit_code, kExitOk);
  const std::string before = test::read_file(out() + "/predictions.csv");
  const auto r = eval("no_samples");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "split.yaml: the 1 session(s) of split(s) no_samples hold no samples")) << r.output;
  EXPECT_EQ(test::read_file(out() + "/predictions.csv"), before);
}

TEST_F(EvalCli, ASessionFolderWithoutItsDescriptionIsNamed) {
  const auto r = eval("unfinished");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "data/unfinished/session.json: missing")) << r.output;
}

TEST_F(EvalCli, UnknownSplitIsBadInput) {
  const auto r = eval("nosuch");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "no split 'nosuch' (it has: ")) << r.output;
}

}  // namespace
}  // namespace ivoa
