// The introspection process logic on memq:// with a two-view model: frames
// before the rig calibration are counted and skipped; after it, each frame
// gives heatmaps of the left image's size.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "introspection_node.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "model_file.hpp"
#include "networks.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

// What the process logs while it lives (the default logger's lines); the
// logger before it is put back however the test ends.
class CapturedLog {
 public:
  CapturedLog() {
    spdlog::set_default_logger(
        std::make_shared<spdlog::logger>("capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(text_)));
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  CapturedLog(const CapturedLog&) = delete;
  CapturedLog& operator=(const CapturedLog&) = delete;
  std::string text() const { return text_.str(); }

 private:
  std::shared_ptr<spdlog::logger> previous_ = spdlog::default_logger();
  std::ostringstream text_;
};

std::string write_model(const test::TempDir& dir, int views, double patch_scale = 0,
                        std::vector<cv::Size> image_sizes = {}) {
  torch::manual_seed(3);
  auto net = introspection::make_network("slidenet", 0.5, views);
  introspection::ModelInfo info;
  info.architecture = "slidenet";
  info.views = views;
  info.patch_scale = patch_scale;
  info.detector = "jppc";
  info.image_sizes = std::move(image_sizes);
  const std::string path = dir.file("model_" + std::to_string(views) + "_" + std::to_string(patch_scale) + "_" +
                                    std::to_string(info.image_sizes.size()) + ".pt");
  introspection::save_model(*net, info, path);
  return path;
}

// The same patch through the network in batches of different sizes may differ
// in the last bits (the CPU's kernels block the work differently), so compare
// probabilities to well below what tells two patches apart.
::testing::AssertionResult same_probabilities(const introspection::Prediction& a, const introspection::Prediction& b) {
  for (size_t k = 0; k < a.probability.size(); ++k)
    if (std::abs(a.probability[k] - b.probability[k]) > 1e-5f)
      return ::testing::AssertionFailure() << "class " << k << ": " << a.probability[k] << " vs " << b.probability[k];
  return ::testing::AssertionSuccess();
}

// The worker runs asynchronously: deliver messages until `done` (bounded, ~6 s).
template <typename Done>
bool deliver_until(Bus& bus, Done done) {
  for (int i = 0; i < 600 && !done(); ++i) {
    bus.handle(5);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

// A node with T = 2 passes that publishes heatmaps only (no obstacle grids);
// `calibration`: the one it starts with (--calibration FILE).
std::unique_ptr<IntrospectionNode> image_only_node(Bus& bus, Heartbeat& heartbeat, const std::string& model_path,
                                                   int queue_frames = 1,
                                                   std::optional<RigCalibration> calibration = std::nullopt) {
  introspection::InferenceConfig config;
  config.mc_passes = 2;
  config.seed = 1;
  IntrospectionNodeOptions options;
  options.grid_channel = "";
  options.queue_frames = queue_frames;
  options.initial_calibration = std::move(calibration);
  return std::make_unique<IntrospectionNode>(bus, heartbeat,
                                             introspection::IntrospectionModel::load(model_path, config), options, 2);
}

stereo_image_t stereo_frame(const RigCalibration& rig, int64_t utime) {
  cv::Mat left(rig.left.height, rig.left.width, CV_8UC3), right(rig.right.height, rig.right.width, CV_8UC3);
  cv::randu(left, 0, 255);
  cv::randu(right, 0, 255);
  stereo_image_t msg;
  msg.utime = utime;
  msg.left = encode_image(left, image_t::PIXEL_FORMAT_BGR, utime);
  msg.right = encode_image(right, image_t::PIXEL_FORMAT_BGR, utime);
  return msg;
}

TEST(IntrospectionNode, TwoViewModelWaitsForTheCalibrationThenRuns) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  const auto node = image_only_node(bus, heartbeat, write_model(dir, 2));
  std::vector<introspection_t> out;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t& m, const ReceiveInfo&) { out.push_back(m); });
  auto wait_for = [&](auto done) { return deliver_until(bus, done); };
  const RigCalibration rig = test::make_test_rig();
  stereo_image_t early = stereo_frame(rig, 1000), frame = stereo_frame(rig, 2000);
  rig_calibration_t calibration = to_message(rig, 1);
  EXPECT_EQ(heartbeat.counter(kFramesWithoutCalibration), 0);
  bus.publish(channels::kStereoImages, early);
  ASSERT_TRUE(wait_for([&] { return heartbeat.counter(kFramesWithoutCalibration) == 1; }));
  EXPECT_TRUE(out.empty());

  bus.publish(channels::kRigCalibration, calibration);
  bus.handle(5);
  bus.publish(channels::kStereoImages, frame);
  ASSERT_TRUE(wait_for([&] { return !out.empty(); }));
  EXPECT_EQ(out[0].utime, 2000);
  EXPECT_EQ(out[0].image_height, rig.left.height);
  EXPECT_EQ(out[0].rows, (rig.left.height - 100) / 20 + 1);
  EXPECT_EQ(out[0].cols, (rig.left.width - 100) / 20 + 1);
  EXPECT_EQ(heartbeat.counter(kFramesWithoutCalibration), 1);
  EXPECT_EQ(heartbeat.bad_input_count(), 0) << "a frame before the calibration is not bad input";

  // A left image of another size than the calibration's: named as such (it was an OpenCV
  // assertion blamed on the right image), skipped, and the next frame runs.
  stereo_image_t smaller = stereo_frame(rig, 3000);
  cv::Mat small(rig.left.height / 2, rig.left.width / 2, CV_8UC3, cv::Scalar::all(90));
  smaller.left = encode_image(small, image_t::PIXEL_FORMAT_BGR, 3000);
  bus.publish(channels::kStereoImages, smaller);
  ASSERT_TRUE(wait_for([&] { return heartbeat.bad_input_count() == 1; }));
  const std::string sizes = "left image " + std::to_string(small.cols) + "x" + std::to_string(small.rows) +
                            " and right " + std::to_string(rig.right.width) + "x" + std::to_string(rig.right.height);
  EXPECT_NE(heartbeat.snapshot().last_error.find(sizes), std::string::npos) << heartbeat.snapshot().last_error;
  stereo_image_t next = stereo_frame(rig, 4000);
  bus.publish(channels::kStereoImages, next);
  ASSERT_TRUE(wait_for([&] { return out.size() == 2; }));
  EXPECT_EQ(out[1].utime, 4000);
}

// --calibration FILE: a respawned process ran nothing until the channel's
// next calibration (up to a second).
TEST(IntrospectionNode, TwoViewModelGivenACalibrationRunsTheFirstFrame) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  const RigCalibration rig = test::make_test_rig();
  const CapturedLog log;  // the warps built, counted below
  const auto node = image_only_node(bus, heartbeat, write_model(dir, 2), 1, rig);
  std::vector<introspection_t> out;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t& m, const ReceiveInfo&) { out.push_back(m); });
  stereo_image_t first = stereo_frame(rig, 1000);
  bus.publish(channels::kStereoImages, first);
  ASSERT_TRUE(deliver_until(bus, [&] { return !out.empty(); }));
  EXPECT_EQ(out[0].utime, 1000);
  EXPECT_EQ(heartbeat.counter(kFramesWithoutCalibration), 0);
  // The same calibration again on the channel is not a new one: nothing is skipped or refused.
  rig_calibration_t again = to_message(rig, 1);
  bus.publish(channels::kRigCalibration, again);
  stereo_image_t second = stereo_frame(rig, 2000);
  bus.publish(channels::kStereoImages, second);
  ASSERT_TRUE(deliver_until(bus, [&] { return out.size() == 2; }));
  EXPECT_EQ(heartbeat.bad_input_count(), 0);
  node->stop();  // the worker logs no more while the log is read
  const std::string said = log.text();
  const size_t built = said.find("ground warp built");
  ASSERT_NE(built, std::string::npos) << said;
  EXPECT_EQ(said.find("ground warp built", built + 1), std::string::npos) << "built again for the same rig:\n" << said;
}

// `n` stereo frames (utimes 1000, 2000, ...) delivered at once, far faster
// than one inference.
void publish_burst(Bus& bus, int n) {
  const RigCalibration rig = test::make_test_rig();
  for (int i = 0; i < n; ++i) {
    stereo_image_t frame = stereo_frame(rig, 1000 * (i + 1));
    bus.publish(channels::kStereoImages, frame);
  }
  for (int i = 0; i < n; ++i) bus.handle(5);
}

// A burst of frames while the network is busy: the mailbox keeps only the
// newest, and each frame it replaces is counted as dropped in the heartbeat
// (the launcher's DROP column), so every frame received is accounted for.
TEST(IntrospectionNode, FramesSkippedWhileBusyAreCountedAsDropped) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  const auto node = image_only_node(bus, heartbeat, write_model(dir, 1));
  int published = 0;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t&, const ReceiveInfo&) { ++published; });
  constexpr int kBurst = 6;
  publish_burst(bus, kBurst);
  const auto accounted = [&] {
    const process_status_t s = heartbeat.snapshot();
    return s.messages_out + s.dropped == kBurst && published == s.messages_out;  // and each output delivered
  };
  ASSERT_TRUE(deliver_until(bus, accounted)) << "out " << heartbeat.snapshot().messages_out << ", dropped "
                                             << heartbeat.snapshot().dropped << " of " << kBurst;
  const process_status_t s = heartbeat.snapshot();
  EXPECT_EQ(s.messages_in, kBurst);
  EXPECT_GE(s.dropped, 1) << "the burst arrived while the first frame was still being processed";
}

// With a queue every frame of a burst is run, in order (a log read as fast
// as it can be, with ?speed=0).
TEST(IntrospectionNode, WithAQueueEveryFrameOfABurstIsRun) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  constexpr int kBurst = 6;
  const auto node = image_only_node(bus, heartbeat, write_model(dir, 1), kBurst);
  std::vector<int64_t> published;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t& m, const ReceiveInfo&) { published.push_back(m.utime); });
  publish_burst(bus, kBurst);
  ASSERT_TRUE(deliver_until(bus, [&] { return published.size() == kBurst; })) << published.size() << " published";
  for (int i = 0; i < kBurst; ++i) EXPECT_EQ(published[static_cast<size_t>(i)], 1000 * (i + 1));
  EXPECT_EQ(heartbeat.snapshot().dropped, 0);
}

// Stopped right after a burst, the node still runs the frame waiting in its
// mailbox: every frame received is either published or counted as dropped
// in the final heartbeat, none silently left behind; frames that never
// arrived (seq 3 and 4 of 0, 1, 2, 5) are counted as missed.
TEST(IntrospectionNode, StopRunsTheFrameStillWaitingSoEveryFrameIsAccountedFor) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  const auto node = image_only_node(bus, heartbeat, write_model(dir, 1));
  const RigCalibration rig = test::make_test_rig();
  constexpr int kBurst = 4;
  for (int i = 0; i < kBurst; ++i) {
    stereo_image_t frame = stereo_frame(rig, 1000 * (i + 1));
    frame.seq = i + 1 < kBurst ? i : i + 2;
    bus.publish(channels::kStereoImages, frame);
  }
  for (int i = 0; i < kBurst; ++i) bus.handle(5);
  node->stop();
  const process_status_t s = heartbeat.snapshot();
  EXPECT_EQ(s.messages_in, kBurst);
  EXPECT_EQ(heartbeat.counter(kFramesMissed), 2);
  EXPECT_EQ(s.messages_out + s.dropped, kBurst) << "out " << s.messages_out << ", dropped " << s.dropped;
  EXPECT_EQ(node->frames_done(), s.messages_out);
}

// The warm-up runs every path a frame takes (heatmaps over both views,
// the near cells' own squares) on a blank frame, then the node works as
// without it.
TEST(IntrospectionNode, WarmsUpOnABlankFrameThenRunsAsUsual) {
  test::TempDir dir;
  introspection::InferenceConfig config;
  config.mc_passes = 2;
  const auto scaled_two_views = introspection::IntrospectionModel::load(write_model(dir, 2, 1.6), config);
  EXPECT_GT(warm_up(*scaled_two_views, cv::Size(320, 240)), 0.0);

  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  IntrospectionNodeOptions options;
  options.grid_channel = "";
  const RigCalibration rig = test::make_test_rig();
  options.warm_up = cv::Size(rig.left.width, rig.left.height);
  IntrospectionNode node(bus, heartbeat, introspection::IntrospectionModel::load(write_model(dir, 1), config), options,
                         2);
  EXPECT_EQ(heartbeat.snapshot().state, "running") << "the constructor returns once warmed up";
  std::vector<introspection_t> out;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t& m, const ReceiveInfo&) { out.push_back(m); });
  stereo_image_t frame = stereo_frame(rig, 5000);
  bus.publish(channels::kStereoImages, frame);
  ASSERT_TRUE(deliver_until(bus, [&] { return !out.empty(); }));
  EXPECT_EQ(out[0].utime, 5000);
  EXPECT_EQ(heartbeat.bad_input_count(), 0);
}

// Frames of a size the model was not trained on are run (patches are cut on
// the ground and resized) but counted, so the status table shows a model on
// a camera it has never seen; the warm-up defaults to the size it knows.
TEST(IntrospectionNode, FramesOfASizeTheModelWasNotTrainedOnAreCounted) {
  test::TempDir dir;
  const RigCalibration rig = test::make_test_rig();
  const cv::Size trained(rig.left.width, rig.left.height), other(trained.width + 40, 240), third(200, 200);
  const auto frame_of_size = [](cv::Size size, int64_t utime) {
    cv::Mat image(size, CV_8UC3);
    cv::randu(image, 0, 255);
    stereo_image_t msg;
    msg.utime = utime;
    msg.left = encode_image(image, image_t::PIXEL_FORMAT_BGR, utime);
    msg.right = msg.left;
    return msg;
  };
  const CapturedLog log;  // the node's warnings, counted below
  {
    Bus bus("memq://");
    Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
    const auto node = image_only_node(bus, heartbeat, write_model(dir, 1, 0, {trained}), 8);
    EXPECT_EQ(heartbeat.counter("frames_untrained_size"), 0) << "shown from the start";
    int published = 0;
    bus.subscribe<introspection_t>(channels::kIntrospection,
                                   [&](const introspection_t&, const ReceiveInfo&) { ++published; });
    const std::vector<std::pair<cv::Size, int64_t>> frames{{trained, 1000}, {other, 2000}, {other, 3000},
                                                           {trained, 4000}, {other, 5000}, {third, 6000}};
    for (const auto& [size, utime] : frames) {
      stereo_image_t frame = frame_of_size(size, utime);
      bus.publish(channels::kStereoImages, frame);
    }
    ASSERT_TRUE(deliver_until(bus, [&] { return published == 6; })) << published << " published";
    node->stop();
    EXPECT_EQ(heartbeat.counter("frames_untrained_size"), 4);
    EXPECT_EQ(heartbeat.bad_input_count(), 0) << "another size is not bad input";
  }
  const std::string said = log.text();
  const auto warnings_of = [&](cv::Size size) {
    const std::string what = std::to_string(size.width) + "x" + std::to_string(size.height) + " images, but model";
    size_t n = 0;
    for (size_t at = said.find(what); at != std::string::npos; at = said.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(warnings_of(other), 1u) << "once per size, not at each change back to it:\n" << said;
  EXPECT_EQ(warnings_of(third), 1u) << said;
  EXPECT_EQ(warnings_of(trained), 0u) << said;
  EXPECT_NE(
      said.find("was trained on " + std::to_string(trained.width) + "x" + std::to_string(trained.height) + " images"),
      std::string::npos)
      << said;

  {
    Bus bus("memq://");
    Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
    const auto node = image_only_node(bus, heartbeat, write_model(dir, 1), 8);
    EXPECT_FALSE(heartbeat.counter("frames_untrained_size").has_value()) << "a model that does not say: no count";
  }

  introspection::InferenceConfig config;
  config.mc_passes = 1;
  EXPECT_EQ(
      default_warm_up_size(introspection::IntrospectionModel::load(write_model(dir, 1, 0, {trained}), config)->info()),
      trained);
  EXPECT_EQ(default_warm_up_size(introspection::IntrospectionModel::load(write_model(dir, 1), config)->info()),
            cv::Size(960, 600))
      << "a model that does not say: the simulator's camera";
}

TEST(IntrospectionNode, ScaledModelPredictsQueryCellsFromTheirOwnPatches) {
  test::TempDir dir;
  introspection::InferenceConfig config;
  config.mc_passes = 1;
  config.mean_filter = 1;
  const RigCalibration rig = test::make_test_rig();
  const QueryGrid query_grid(QueryGridConfig{}, RigGeometry(rig).left);
  const obstacle_grid_t grid = make_obstacle_grid(query_grid, "jppc", 1000);
  cv::Mat image(rig.left.height, rig.left.width, CV_8UC3);
  cv::randu(image, 0, 255);
  std::vector<introspection::IntrospectionModel::CellPatch> cells;
  const auto sides = footprint_patch_sides(grid, 100, image.size(), 1.6);
  for (size_t i = 0; i < grid.state.size(); ++i)
    if (grid.in_image[i]) cells.push_back({grid.u[i], grid.v[i], sides[i]});
  ASSERT_GT(cells.size(), 10u);

  // Near cells come from their own scaled squares, the rest from the heatmaps.
  const auto scaled = introspection::IntrospectionModel::load(write_model(dir, 1, 1.6), config);
  const auto h = scaled->run(image);
  const auto got = query_predictions(*scaled, h, image, grid);
  const auto own = scaled->predict_cells(image, cells);
  ASSERT_EQ(got.size(), cells.size());
  int own_squares = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    const bool near = cells[i].side > 100;
    own_squares += near;
    const auto want = near ? own[i] : scaled->predict_at(h, cells[i].u, cells[i].v);
    EXPECT_TRUE(same_probabilities(got[i], want)) << "cell " << i << ", side " << cells[i].side;
    if (near) {
      EXPECT_FALSE(same_probabilities(got[i], scaled->predict_at(h, cells[i].u, cells[i].v))) << i;
    }
  }
  EXPECT_GT(own_squares, 0);
  EXPECT_LT(own_squares, static_cast<int>(cells.size()));

  const auto fixed = introspection::IntrospectionModel::load(write_model(dir, 1), config);
  const auto hf = fixed->run(image);
  const auto from_heatmap = query_predictions(*fixed, hf, image, grid);
  ASSERT_EQ(from_heatmap.size(), cells.size());
  for (size_t i = 0; i < cells.size(); ++i)
    EXPECT_EQ(from_heatmap[i].probability, fixed->predict_at(hf, cells[i].u, cells[i].v).probability) << "cell " << i;
  const introspection_t msg =
      make_introspection_message(*fixed, hf, 1000, image.cols, image.rows, &grid, from_heatmap, 1, false);
  EXPECT_EQ(msg.query_class.size(), cells.size());
  EXPECT_EQ(msg.query_verdict.size(), cells.size());
}

TEST(IntrospectionNode, QueryCellsAreGivenTheVerdictsOfTheirOwnFrame) {
  test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "introspection", "NODE_TEST_STATUS", 3600.0);
  introspection::InferenceConfig config;
  config.mc_passes = 4;
  config.seed = 2;
  config.verdict_uncertainty_threshold = 1.0;  // every verdict prediction announced
  IntrospectionNodeOptions options;
  options.grid_wait = std::chrono::milliseconds(50);
  IntrospectionNode node(bus, heartbeat, introspection::IntrospectionModel::load(write_model(dir, 1), config), options,
                         4);
  std::vector<introspection_t> out;
  bus.subscribe<introspection_t>(channels::kIntrospection,
                                 [&](const introspection_t& m, const ReceiveInfo&) { out.push_back(m); });
  auto wait_for = [&](auto done) { return deliver_until(bus, done); };
  const RigCalibration rig = test::make_test_rig();
  const QueryGrid query_grid(QueryGridConfig{}, RigGeometry(rig).left);
  obstacle_grid_t grid = make_obstacle_grid(query_grid, "jppc", 2000);
  std::vector<int8_t> verdicts;  // of the in-image cells, in order
  for (size_t i = 0; i < grid.state.size(); ++i) {
    grid.state[i] = static_cast<int8_t>(i % 3);  // free, obstacle, unknown
    if (grid.in_image[i]) verdicts.push_back(grid.state[i]);
  }
  bus.publish(channels::kObstaclesStereo, grid);
  bus.handle(5);
  stereo_image_t frame = stereo_frame(rig, 2000);
  bus.publish(channels::kStereoImages, frame);
  ASSERT_TRUE(wait_for([&] { return out.size() == 1; }));
  const introspection_t& m = out[0];
  ASSERT_EQ(m.query_verdict, verdicts);
  for (size_t q = 0; q < verdicts.size(); ++q) {
    const int8_t c = m.query_verdict_class[q];
    if (verdicts[q] == obstacle_grid_t::STATE_UNKNOWN) {
      EXPECT_EQ(c, introspection_labels_t::LABEL_NONE);
      EXPECT_TRUE(std::isnan(m.query_p_wrong[q]));
      continue;
    }
    const bool obstacle = verdicts[q] == obstacle_grid_t::STATE_OBSTACLE;
    const bool wrong = m.query_p_wrong[q] > 0.5f;
    EXPECT_EQ(c, obstacle ? (wrong ? introspection_labels_t::LABEL_FP : introspection_labels_t::LABEL_TP)
                          : (wrong ? introspection_labels_t::LABEL_FN : introspection_labels_t::LABEL_TN));
    EXPECT_GE(m.query_p_wrong_variance[q], 0.0f);
    EXPECT_EQ(m.query_verdict_announced[q], 1);
  }
  EXPECT_FLOAT_EQ(m.verdict_uncertainty_threshold, 1.0f);

  // A frame whose grid never comes: the geometry of the last grid, no verdicts, counted.
  stereo_image_t next = stereo_frame(rig, 3000);
  bus.publish(channels::kStereoImages, next);
  ASSERT_TRUE(wait_for([&] { return out.size() == 2; }));
  ASSERT_EQ(out[1].query_verdict.size(), verdicts.size());
  for (size_t q = 0; q < verdicts.size(); ++q) EXPECT_EQ(out[1].query_verdict[q], obstacle_grid_t::STATE_UNKNOWN);
  EXPECT_EQ(heartbeat.counter("grids_missing"), 1);

  // Another detector's grid of the frame: its geometry, not its verdicts.
  grid.utime = 4000;
  grid.detector = "dense";
  bus.publish(channels::kObstaclesStereo, grid);
  bus.handle(5);
  stereo_image_t third = stereo_frame(rig, 4000);
  bus.publish(channels::kStereoImages, third);
  ASSERT_TRUE(wait_for([&] { return out.size() == 3; }));
  ASSERT_EQ(out[2].query_verdict.size(), verdicts.size());
  for (size_t q = 0; q < verdicts.size(); ++q) {
    EXPECT_EQ(out[2].query_verdict[q], obstacle_grid_t::STATE_UNKNOWN);
    EXPECT_EQ(out[2].query_verdict_class[q], introspection_labels_t::LABEL_NONE);
  }
  EXPECT_EQ(heartbeat.counter("grids_other_detector"), 1);
  EXPECT_EQ(heartbeat.counter("grids_missing"), 1) << "the frame's grid came";

  // A grid with a cell in view but no pixel: bad input, not predictions at NaN; the last good grid's
  // geometry serves its frame.
  grid.utime = 5000;
  grid.detector = "jppc";
  const size_t seen =
      static_cast<size_t>(std::find(grid.in_image.begin(), grid.in_image.end(), 1) - grid.in_image.begin());
  grid.u[seen] = std::nanf("");
  bus.publish(channels::kObstaclesStereo, grid);
  bus.handle(5);
  EXPECT_EQ(heartbeat.bad_input_count(), 1);
  EXPECT_NE(heartbeat.snapshot().last_error.find("in_image, but its pixel (nan"), std::string::npos);
  stereo_image_t fifth = stereo_frame(rig, 5000);
  bus.publish(channels::kStereoImages, fifth);
  ASSERT_TRUE(wait_for([&] { return out.size() == 4; }));
  for (float u : out[3].query_u) EXPECT_TRUE(std::isfinite(u));
  EXPECT_EQ(heartbeat.counter("grids_missing"), 2);
}

TEST(RecentGrids, FindsTheFrameOrStopsWaitingOnceANewerOneIsIn) {
  RecentGrids grids;
  obstacle_grid_t g;
  g.utime = 100;
  grids.put(g);
  g.utime = 300;
  grids.put(g);
  EXPECT_EQ(grids.of_frame(100, std::chrono::milliseconds(0))->utime, 100);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(grids.of_frame(200, std::chrono::seconds(30)).has_value());  // 300 is in: 200's will not come
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_EQ(grids.latest()->utime, 300);
  std::thread late([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    obstacle_grid_t next;
    next.utime = 400;
    grids.put(next);
  });
  EXPECT_EQ(grids.of_frame(400, std::chrono::seconds(30))->utime, 400);  // woken by its arrival
  late.join();
  // At a stop no grid arrives any more: a wait ends at once (it used to run
  // its whole --grid-wait-ms, up to a minute, per frame left).
  std::thread stopping([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    grids.close();
  });
  const auto before_close = std::chrono::steady_clock::now();
  EXPECT_FALSE(grids.of_frame(500, std::chrono::seconds(30)).has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - before_close, std::chrono::seconds(10));
  stopping.join();
  EXPECT_EQ(grids.of_frame(400, std::chrono::seconds(30))->utime, 400);  // what arrived is still found
}

}  // namespace
}  // namespace ivoa
