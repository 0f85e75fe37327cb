// Model files round-trip exactly with their metadata; bad files are refused
// with the reason; full-frame heatmaps agree with patch-by-patch inference.
#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/query_grid.hpp"
#include "ivoa/introspection/model.hpp"
#include "model_file.hpp"
#include "networks.hpp"
#include "test_rig.hpp"

namespace ivoa::introspection {
namespace {

std::string write_random_model(const test::TempDir& dir, const std::string& architecture = "slidenet", int views = 1,
                               double patch_scale = 0) {
  torch::manual_seed(9);
  auto net = make_network(architecture, 0.5, views);
  ModelInfo info;
  info.views = views;
  info.patch_scale = patch_scale;
  info.architecture = architecture;
  info.input_size = input_size_of(architecture);
  info.detector = "jppc";
  info.uncertainty_threshold = 0.0123;
  info.verdict_uncertainty_threshold = 0.0045;
  info.training_summary = "{\"steps\": 7}";
  const std::string path = dir.file(architecture + std::to_string(views) + (patch_scale > 0 ? "_scaled" : "") + ".pt");
  save_model(*net, info, path);
  return path;
}

// One deterministic pass and no mean filter: heatmap cells equal their patches.
InferenceConfig one_pass_unfiltered() {
  InferenceConfig c;
  c.mc_passes = 1;
  c.mean_filter = 1;
  return c;
}

cv::Mat random_image(int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  cv::randu(m, 0, 255);
  return m;
}

TEST(ModelFile, SavedAndLoadedModelGivesIdenticalOutputsAndMetadata) {
  test::TempDir dir;
  const std::string path = write_random_model(dir);
  InferenceConfig deterministic;
  deterministic.mc_passes = 1;
  const auto a = IntrospectionModel::load(path, deterministic);
  const auto b = IntrospectionModel::load(path, deterministic);
  EXPECT_EQ(a->info().architecture, "slidenet");
  EXPECT_EQ(a->info().detector, "jppc");
  EXPECT_DOUBLE_EQ(a->info().uncertainty_threshold, 0.0123);
  EXPECT_DOUBLE_EQ(a->info().verdict_uncertainty_threshold, 0.0045);
  EXPECT_DOUBLE_EQ(a->verdict_threshold(), 0.0045);
  EXPECT_NE(a->info().training_summary.find("steps"), std::string::npos);
  EXPECT_NE(a->info().id.find("slidenet1.pt#"), std::string::npos);
  EXPECT_EQ(a->info().views, 1);
  const cv::Mat image = random_image(300, 220);
  const Heatmaps ha = a->run(image), hb = b->run(image);
  for (int k = 0; k < kNumClasses; ++k)
    EXPECT_EQ(cv::norm(ha.probability[static_cast<size_t>(k)], hb.probability[static_cast<size_t>(k)], cv::NORM_INF),
              0);
}

// The camera sizes a model was trained on travel with it, so the tools can
// say when it is run on another camera; older files say nothing, and then
// no size is called untrained.
TEST(ModelFile, TheTrainingImageSizesTravelWithTheModel) {
  ModelInfo info;
  info.detector = "jppc";
  info.image_sizes = {{960, 600}, {640, 480}};
  const ModelInfo read = info_from_json(info_to_json(info), "here");
  EXPECT_EQ(read.image_sizes, info.image_sizes);
  EXPECT_TRUE(trained_on_size(read, {640, 480}));
  EXPECT_FALSE(trained_on_size(read, {1280, 720}));
  EXPECT_EQ(image_sizes_text(read.image_sizes), "960x600, 640x480");

  std::string older = info_to_json(ModelInfo{});
  const size_t key = older.find(", \"image_sizes\": []");
  ASSERT_NE(key, std::string::npos) << older;
  older.erase(key, std::string(", \"image_sizes\": []").size());
  const ModelInfo old_model = info_from_json(older, "older.pt");
  EXPECT_TRUE(old_model.image_sizes.empty());
  EXPECT_TRUE(trained_on_size(old_model, {1280, 720}));
  EXPECT_EQ(image_sizes_text(old_model.image_sizes), "not recorded");

  // Each refused, the message saying what is expected and what was found.
  for (const auto& [written, wrong] :
       std::vector<std::pair<std::string, std::string>>{{"[[960, 600], [640, 0]]", "[640, 0]"},
                                                        {"[960, 600]", "960"},
                                                        {"[\"960x600\"]", "\"960x600\""},
                                                        {"[[960, 600.5]]", "[960, 600.5]"},
                                                        {"[[100000, 100000]]", "[100000, 100000]"}}) {
    std::string bad = info_to_json(info);
    bad.replace(bad.find("[[960, 600], [640, 480]]"), 24, written);
    try {
      info_from_json(bad, "bad.pt");
      FAIL() << written << " was read";
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.pt: image_sizes must be a list of [width, height] pairs"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(", not " + wrong), std::string::npos) << e.what();
    }
  }
}

// The training summary is JSON that eval.json quotes: read and written back,
// its numbers stay numbers and its strings strings (every value came back
// quoted, "steps": "14000"); a NaN, which no JSON reader takes, is quoted.
TEST(ModelFile, TheTrainingSummaryKeepsItsTypes) {
  ModelInfo info;
  info.detector = "jppc";
  info.training_summary =
      R"({"steps": 7, "name": "7", "rate": 1e-05, "augment": true, "val": nan, "list": [1, "a"], "none": {}})";
  const ModelInfo read = info_from_json(info_to_json(info), "here");
  EXPECT_EQ(read.training_summary,
            R"({"steps": 7, "name": "7", "rate": 1e-05, "augment": true, "val": "nan", "list": [1, "a"], "none": {}})");
}

TEST(ModelFile, HeatmapCellsEqualTheirPatches) {
  test::TempDir dir;
  const InferenceConfig c = one_pass_unfiltered();
  const auto model = IntrospectionModel::load(write_random_model(dir), c);
  const cv::Mat image = random_image(340, 260);
  const Heatmaps h = model->run(image);
  ASSERT_EQ(h.rows, 9);
  ASSERT_EQ(h.cols, 13);
  std::vector<cv::Mat> patches;
  for (int r = 0; r < h.rows; ++r)
    for (int col = 0; col < h.cols; ++col) patches.push_back(image(cv::Rect(col * 20, r * 20, 100, 100)).clone());
  const PatchOutputs out = model->run_patches(patches, true);
  ASSERT_EQ(out.predictions.size(), patches.size());
  ASSERT_EQ(out.embeddings.size(), patches.size());
  EXPECT_EQ(out.embeddings[0].size(), 256u);
  for (int r = 0; r < h.rows; ++r)
    for (int col = 0; col < h.cols; ++col)
      for (int k = 0; k < kNumClasses; ++k)
        EXPECT_NEAR(h.probability[static_cast<size_t>(k)].at<float>(r, col),
                    out.predictions[static_cast<size_t>(r * h.cols + col)].probability[static_cast<size_t>(k)], 1e-5);
}

TEST(ModelFile, CellPredictionsComeFromTheirOwnResizedSquares) {
  test::TempDir dir;
  const InferenceConfig c = one_pass_unfiltered();
  const auto model = IntrospectionModel::load(write_random_model(dir, "slidenet", 2, 1.6), c);
  EXPECT_DOUBLE_EQ(model->info().patch_scale, 1.6);
  const cv::Mat image = random_image(400, 2 * 300);  // two stacked 400 x 300 views
  const std::vector<IntrospectionModel::CellPatch> cells{{190, 150, 100}, {200, 150, 240}, {120, 200, 160}};
  const auto predictions = model->predict_cells(image, cells);
  ASSERT_EQ(predictions.size(), 3u);
  for (size_t i = 0; i < cells.size(); ++i) {
    std::vector<cv::Mat> views;
    for (int k = 0; k < 2; ++k) {
      cv::Mat part = image(patch_rect(cells[i].u, cells[i].v + k * 300, cells[i].side)), resized;
      cv::resize(part, resized, {100, 100}, 0, 0, cv::INTER_AREA);
      views.push_back(resized);
    }
    cv::Mat stacked;
    cv::vconcat(views, stacked);
    const auto want = model->run_patches({stacked}, false).predictions[0];
    for (int k = 0; k < kNumClasses; ++k)
      EXPECT_NEAR(predictions[i].probability[static_cast<size_t>(k)], want.probability[static_cast<size_t>(k)], 1e-6)
          << i;
  }
  // The 100 px square at a heatmap cell's centre is that cell's patch.
  const Heatmaps h = model->run(image);
  for (int k = 0; k < kNumClasses; ++k)
    EXPECT_NEAR(predictions[0].probability[static_cast<size_t>(k)],
                h.probability[static_cast<size_t>(k)].at<float>(5, 7), 1e-5);
  EXPECT_THROW(model->predict_cells(image, {{200, 150, 320}}), ModelError);  // leaves the 300-row view
}

TEST(ModelFile, VerdictErrorsAreTheConditionalsAndTheHeatmapsCarryThem) {
  test::TempDir dir;
  const InferenceConfig c = one_pass_unfiltered();
  const auto model = IntrospectionModel::load(write_random_model(dir), c);
  const cv::Mat image = random_image(300, 220);
  const Heatmaps h = model->run(image);
  const auto p = model->run_patches({image(cv::Rect(5 * 20, 3 * 20, 100, 100)).clone()}, false).predictions[0];
  const auto& q = p.probability;
  EXPECT_NEAR(p.verdict_error[0], q[2] / (q[0] + q[2]), 1e-6);  // P(FP | obstacle)
  EXPECT_NEAR(p.verdict_error[1], q[3] / (q[1] + q[3]), 1e-6);  // P(FN | free)
  EXPECT_NEAR(h.verdict_error[0].at<float>(3, 5), p.verdict_error[0], 1e-5);
  EXPECT_NEAR(h.verdict_error[1].at<float>(3, 5), p.verdict_error[1], 1e-5);
  const Prediction at = model->predict_at(h, 150, 110);  // the same cell
  EXPECT_NEAR(at.verdict_error[1], p.verdict_error[1], 1e-5);
}

TEST(ModelFile, GivenTheVerdictOnlyItsTwoClassesArePossible) {
  Prediction p;
  p.probability = {0.1f, 0.6f, 0.2f, 0.1f};  // on its own: TN
  p.verdict_error = {0.2f / 0.3f, 0.1f / 0.7f};
  p.verdict_error_variance = {0.002f, 0.0001f};
  const VerdictPrediction obstacle = given_verdict(p, true, 0.001);
  EXPECT_EQ(obstacle.predicted, 2);  // FP: the detector's obstacle is more likely false
  EXPECT_FLOAT_EQ(obstacle.p_wrong, 0.2f / 0.3f);
  EXPECT_FLOAT_EQ(obstacle.variance, 0.002f);
  EXPECT_FALSE(obstacle.announced);  // above the gate
  const VerdictPrediction free_cell = given_verdict(p, false, 0.001);
  EXPECT_EQ(free_cell.predicted, 1);  // TN
  EXPECT_TRUE(free_cell.announced);
  p.verdict_error = {0.1f, 0.9f};
  EXPECT_EQ(given_verdict(p, true, 1).predicted, 0);   // TP
  EXPECT_EQ(given_verdict(p, false, 1).predicted, 3);  // FN
}

TEST(ModelFile, VerdictGateFallsBackToTheModelGate) {
  test::TempDir dir;
  const std::string path = write_random_model(dir);
  auto net = load_native_model(path);
  net.info.verdict_uncertainty_threshold = -1;  // a model calibrated before the verdict gate existed
  save_model(*net.net, net.info, dir.file("old.pt"));
  InferenceConfig c;
  c.mc_passes = 1;
  EXPECT_DOUBLE_EQ(IntrospectionModel::load(dir.file("old.pt"), c)->verdict_threshold(), 0.0123);
  c.verdict_uncertainty_threshold = 0.5;  // configured: wins
  EXPECT_DOUBLE_EQ(IntrospectionModel::load(dir.file("old.pt"), c)->verdict_threshold(), 0.5);
}

TEST(ModelFile, TwoViewHeatmapCellsEqualTheirStackedPatches) {
  // The image is the left view stacked over the warped right one; each
  // cell's prediction is that of its two squares stacked, as datasets store them.
  test::TempDir dir;
  const InferenceConfig c = one_pass_unfiltered();
  const auto model = IntrospectionModel::load(write_random_model(dir, "slidenet", 2), c);
  EXPECT_EQ(model->info().views, 2);
  const cv::Mat image = random_image(300, 2 * 180);
  const Heatmaps h = model->run(image);
  ASSERT_EQ(h.rows, 5);  // (180 - 100) / 20 + 1
  ASSERT_EQ(h.cols, 11);
  std::vector<cv::Mat> patches;
  for (int r = 0; r < h.rows; ++r)
    for (int col = 0; col < h.cols; ++col) {
      cv::Mat stacked;
      cv::vconcat(image(cv::Rect(col * 20, r * 20, 100, 100)), image(cv::Rect(col * 20, 180 + r * 20, 100, 100)),
                  stacked);
      patches.push_back(stacked);
    }
  const PatchOutputs out = model->run_patches(patches, false);
  for (int r = 0; r < h.rows; ++r)
    for (int col = 0; col < h.cols; ++col)
      for (int k = 0; k < kNumClasses; ++k)
        EXPECT_NEAR(h.probability[static_cast<size_t>(k)].at<float>(r, col),
                    out.predictions[static_cast<size_t>(r * h.cols + col)].probability[static_cast<size_t>(k)], 1e-5);
  // The right view matters: changing it changes the predictions.
  cv::Mat other = image.clone();
  cv::randu(other.rowRange(180, 360), 0, 255);
  EXPECT_GT(cv::norm(model->run(other).probability[0], h.probability[0], cv::NORM_INF), 1e-4);
  EXPECT_THROW(model->run(random_image(300, 181)), ModelError);  // not two stacked views
}

TEST(ModelFile, McHeatmapsHaveVarianceAndGateByThreshold) {
  test::TempDir dir;
  InferenceConfig c;
  c.mc_passes = 20;
  c.seed = 4;
  c.uncertainty_threshold = 1.0;  // everything announced
  const auto model = IntrospectionModel::load(write_random_model(dir), c);
  const Heatmaps h = model->run(random_image(300, 220));
  double max_var = 0;
  cv::minMaxLoc(h.uncertainty, nullptr, &max_var);
  EXPECT_GT(max_var, 0.0);
  const Prediction p = model->predict_at(h, 150, 110);
  EXPECT_TRUE(p.announced);
  EXPECT_NEAR(p.probability[0] + p.probability[1] + p.probability[2] + p.probability[3], 1.0, 1e-4);
  EXPECT_EQ(p.predicted, h.predicted.at<uint8_t>(3, 5));  // (150-50)/20 = 5, (110-50)/20 = 3
}

TEST(ModelFile, BadFilesAreRefusedWithTheReason) {
  test::TempDir dir;
  auto expect_refusal = [](const std::string& path, const std::string& reason) {
    try {
      IntrospectionModel::load(path);
      FAIL() << path;
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  expect_refusal(dir.file("missing.pt"), "no such model file");
  ASSERT_EQ(mkfifo(dir.file("pipe.pt").c_str(), 0600), 0);  // blocked the reader for ever
  expect_refusal(dir.file("pipe.pt"), "pipe.pt: is a pipe, device or socket, not a file");
  EXPECT_THROW(load_native_model(dir.file("pipe.pt")), ModelError);
  expect_refusal(dir.path().string(), "is a folder, not a file");
  std::ofstream(dir.file("garbage.pt")) << "not a model";
  expect_refusal(dir.file("garbage.pt"), "not a TorchScript model");
  // A torch file without our metadata.
  torch::serialize::OutputArchive archive;
  archive.write("w", torch::zeros({3}));
  archive.save_to(dir.file("foreign.pt"));
  expect_refusal(dir.file("foreign.pt"), "no forward()");
  // Metadata claiming another architecture than the weights.
  const std::string slide = write_random_model(dir);
  {
    auto net = make_network("slidenet", 0.5);
    ModelInfo info;
    info.architecture = "alexnet";
    info.input_size = 224;
    const std::string json = info_to_json(info);
    auto t = torch::empty({static_cast<int64_t>(json.size())}, torch::kUInt8);
    std::memcpy(t.data_ptr<uint8_t>(), json.data(), json.size());
    torch::serialize::OutputArchive b;
    net->save(b);
    b.write(kMetadataKey, t, true);
    b.save_to(dir.file("mismatch.pt"));
  }
  expect_refusal(dir.file("mismatch.pt"), "do not fit architecture 'alexnet'");
  // A few bytes flipped in the weights: LibTorch would load them as other numbers.
  std::string bytes;
  {
    std::ifstream in(slide, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  for (size_t k = bytes.size() / 2; k < bytes.size() / 2 + 16; ++k) bytes[k] = static_cast<char>(~bytes[k]);
  std::ofstream(dir.file("flipped.pt"), std::ios::binary) << bytes;
  expect_refusal(dir.file("flipped.pt"), "the model file is damaged");
  EXPECT_NO_THROW(IntrospectionModel::load(slide));
  // What a diverged training would leave: NaN weights, a gate that is no number.
  {
    auto net = make_network("slidenet", 0.5);
    ModelInfo info;
    info.architecture = "slidenet";
    info.input_size = input_size_of("slidenet");
    info.detector = "jppc";
    {
      torch::NoGradGuard no_grad;
      net->parameters().front().fill_(std::numeric_limits<float>::quiet_NaN());
    }
    save_model(*net, info, dir.file("nan_weights.pt"));
    expect_refusal(dir.file("nan_weights.pt"), "holds NaN or infinite weights");
    net = make_network("slidenet", 0.5);
    info.uncertainty_threshold = std::numeric_limits<double>::quiet_NaN();
    save_model(*net, info, dir.file("nan_gate.pt"));
    expect_refusal(dir.file("nan_gate.pt"), "nan_gate.pt: ");
    // an input normalisation that divides by 0: every prediction was NaN, exit 0
    info.uncertainty_threshold = 0.03;
    info.std[1] = 0;
    save_model(*net, info, dir.file("std_0.pt"));
    expect_refusal(dir.file("std_0.pt"), "its input normalisation (mean, std) must be finite numbers with std > 0");
  }
}

// The main job evaluates the shipped model on datasets it builds: they must
// be cut the way the model was trained, which the script states.
TEST(ShippedModel, MetadataMatchesWhatTheMainJobAssumes) {
  const auto model = IntrospectionModel::load(IVOA_SHIPPED_MODEL);
  std::ifstream script(IVOA_MAIN_JOB_SCRIPT);
  std::string line;
  while (std::getline(script, line) && line.rfind("SHIPPED_VIEWS=", 0) != 0) {
  }
  ASSERT_EQ(line.rfind("SHIPPED_VIEWS=", 0), 0u) << "no SHIPPED_VIEWS= line in " << IVOA_MAIN_JOB_SCRIPT;
  int views = 0;
  double scale = -1;
  ASSERT_EQ(std::sscanf(line.c_str(), "SHIPPED_VIEWS=%d SHIPPED_PATCH_SCALE=%lf", &views, &scale), 2) << line;
  EXPECT_EQ(model->info().views, views);
  EXPECT_DOUBLE_EQ(model->info().patch_scale, scale);
  EXPECT_EQ(model->info().detector, "jppc");
  // The simulator's camera, which the live process warms up at.
  EXPECT_EQ(model->info().image_sizes, std::vector<cv::Size>{cv::Size(960, 600)});
}

}  // namespace
}  // namespace ivoa::introspection
