// The depth_monitor process logic on memq://: labels for paired frames,
// and every kind of bad input counted, skipped, and survived.
#include <gtest/gtest.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "monitor_node.hpp"
#include "synthetic_depth.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

using G = obstacle_grid_t;
using L = introspection_labels_t;

struct NodeFixture {
  Bus bus{"memq://"};
  Heartbeat heartbeat{bus, "depth_monitor", "NODE_TEST_STATUS", 3600.0};
  MonitorNode node{bus, heartbeat, MonitorNodeOptions{}};
  RigCalibration rig = test::make_test_rig();
  QueryGrid grid{QueryGridConfig{}, RigGeometry(rig).left};
  std::vector<introspection_labels_t> labels;
  std::vector<obstacle_grid_t> depth_grids;

  NodeFixture() {
    bus.subscribe<introspection_labels_t>(
        channels::kIntrospectionLabels,
        [this](const introspection_labels_t& m, const ReceiveInfo&) { labels.push_back(m); });
    bus.subscribe<obstacle_grid_t>(channels::kObstaclesDepth,
                                   [this](const obstacle_grid_t& m, const ReceiveInfo&) { depth_grids.push_back(m); });
  }
  void drain() {
    while (bus.handle(5) > 0) {
    }
  }
  void send_calibration() {
    rig_calibration_t msg = to_message(rig, 1);
    bus.publish(channels::kRigCalibration, msg);
    drain();
  }
  void send_depth(int64_t utime, const cv::Mat& depth, int64_t seq = 0) {
    depth_image_t msg = encode_depth(depth, 570, 570, 319.5, 240.25, utime);
    msg.seq = seq;
    bus.publish(channels::kDepthImage, msg);
    drain();
  }
  // A stereo verdict that says FREE everywhere except at cell `obstacle_cell`.
  void send_stereo(int64_t utime, int obstacle_cell) {
    obstacle_grid_t msg = make_obstacle_grid(grid, "jppc", utime);
    for (auto& s : msg.state) s = G::STATE_FREE;
    msg.state[static_cast<size_t>(obstacle_cell)] = G::STATE_OBSTACLE;
    bus.publish(channels::kObstaclesStereo, msg);
    drain();
  }
};

TEST(MonitorNode, LabelsPairedFramesAgainstTheDepthVerdict) {
  NodeFixture f;
  f.send_calibration();
  test::DepthScene scene;
  scene.boxes.push_back({1.55, 1.9, -0.3, 0.2, 0.4});
  const cv::Mat depth = test::render_depth(f.rig, scene);
  const int box_cell = f.grid.index(4, 6);    // x = 1.5, y = 0: 5 cm from the box
  const int floor_cell = f.grid.index(2, 6);  // x = 1.0, y = 0: clear floor
  f.send_depth(1'000'000, depth);
  f.send_stereo(997'000, floor_cell);  // stereo sees an obstacle on the clear floor, misses the box
  ASSERT_EQ(f.labels.size(), 1u);
  ASSERT_EQ(f.depth_grids.size(), 1u);
  const auto& l = f.labels[0];
  EXPECT_EQ(l.utime, 997'000);
  EXPECT_EQ(l.depth_utime, 1'000'000);
  EXPECT_EQ(f.depth_grids[0].depth_utime, 1'000'000);
  EXPECT_EQ(f.depth_grids[0].detector, "depth_monitor");
  EXPECT_EQ(l.label[static_cast<size_t>(box_cell)], L::LABEL_FN);
  EXPECT_EQ(l.label[static_cast<size_t>(floor_cell)], L::LABEL_FP);
  EXPECT_EQ(l.label[static_cast<size_t>(f.grid.index(2, 7))], L::LABEL_TN);  // x = 1.0, y = 0.25
  EXPECT_EQ(f.heartbeat.bad_input_count(), 0);
}

// A depth frame whose own intrinsics are not the calibration's (fx 100
// against 570) was labelled in silence: still labelled with the
// calibration's, but counted (and warned of once).
TEST(MonitorNode, DepthFramesOfOtherIntrinsicsAreCounted) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat depth = test::render_depth(f.rig, test::DepthScene{});
  f.send_depth(1'000'000, depth);
  EXPECT_EQ(f.heartbeat.counter("depth_intrinsics_differ"), 0);
  depth_image_t other = encode_depth(depth, 100, 100, 10, 10, 2'000'000);
  f.bus.publish(channels::kDepthImage, other);
  f.drain();
  EXPECT_EQ(f.heartbeat.counter("depth_intrinsics_differ"), 1);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 0);
}

// A process started a moment before the drivers sees inputs before the
// first RIG_CALIBRATION: skipped and counted, but not as bad input.
TEST(MonitorNode, InputsBeforeTheCalibrationAreCountedApartFromBadInput) {
  NodeFixture f;
  EXPECT_EQ(f.heartbeat.counter(kFramesWithoutCalibration), 0);
  f.send_depth(1'000, test::render_depth(f.rig, {}));
  f.send_stereo(1'000, 0);
  EXPECT_EQ(f.heartbeat.counter(kFramesWithoutCalibration), 2);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 0);
  EXPECT_EQ(f.heartbeat.snapshot().state, "waiting for calibration");
  EXPECT_TRUE(f.labels.empty());

  f.send_calibration();
  f.send_depth(100'000, test::render_depth(f.rig, {}));
  f.send_stereo(100'000, 0);
  EXPECT_EQ(f.labels.size(), 1u);
  EXPECT_EQ(f.heartbeat.counter(kFramesWithoutCalibration), 2);
  EXPECT_EQ(f.heartbeat.snapshot().state, "running");
}

// --calibration FILE: a respawned monitor skipped its first frames until
// the driver's next RIG_CALIBRATION (up to a second).
TEST(MonitorNode, GivenACalibrationItLabelsTheFirstFrames) {
  NodeFixture f;
  f.node.set_calibration(f.rig);
  EXPECT_EQ(f.heartbeat.snapshot().state, "running");
  f.send_depth(1'000, test::render_depth(f.rig, {}));
  f.send_stereo(1'000, 0);
  EXPECT_EQ(f.labels.size(), 1u);
  EXPECT_EQ(f.heartbeat.counter(kFramesWithoutCalibration), 0);
  // The same rig again on the channel is no change: a rebuild would flush the depth frame waiting
  // for its stereo grid, and that grid would go unlabelled.
  f.send_depth(100'000, test::render_depth(f.rig, {}));
  f.send_calibration();
  f.send_stereo(100'000, 0);
  EXPECT_EQ(f.labels.size(), 2u);
  EXPECT_EQ(f.heartbeat.counter("frames_labelled"), 2);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 0);
}

// A new calibration rebuilds the monitor: its counts went back to 0 (the
// summary said 2 frames labelled of 4).
TEST(MonitorNode, CountsAreOfTheWholeRunAcrossACalibrationChange) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat floor = test::render_depth(f.rig, {});
  f.send_depth(100'000, floor);
  f.send_stereo(100'000, 0);
  f.rig.rig_name = "recalibrated";
  f.send_calibration();
  f.send_depth(200'000, floor);
  f.send_stereo(200'000, 0);
  EXPECT_EQ(f.labels.size(), 2u);
  EXPECT_EQ(f.heartbeat.counter("frames_labelled"), 2);
}

// Depth frames lost on the way (seq gaps) are counted, as the detector does.
TEST(MonitorNode, DepthFramesThatNeverArrivedAreCounted) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat floor = test::render_depth(f.rig, {});
  for (const int64_t seq : {4, 5, 9}) f.send_depth(seq * 100'000, floor, seq);
  EXPECT_EQ(f.heartbeat.counter(kFramesMissed), 3);
}

TEST(MonitorNode, BadInputIsCountedSkippedAndSurvived) {
  NodeFixture f;
  const cv::Mat ground = test::render_depth(f.rig, {});
  f.send_calibration();
  f.send_depth(2'000, cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)));  // zero-filled
  EXPECT_EQ(f.heartbeat.bad_input_count(), 1);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find("zero-filled"), std::string::npos);

  f.send_depth(3'000, cv::Mat(240, 320, CV_16UC1, cv::Scalar(1500)));  // wrong size
  EXPECT_EQ(f.heartbeat.bad_input_count(), 2);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find("320x240"), std::string::npos);

  depth_image_t nan_intrinsics = encode_depth(ground, std::nan(""), 570, 320, 240, 4'000);
  f.bus.publish(channels::kDepthImage, nan_intrinsics);
  f.drain();
  EXPECT_EQ(f.heartbeat.bad_input_count(), 3);

  QueryGridConfig other;
  other.spacing = 0.2;
  obstacle_grid_t wrong_grid = make_obstacle_grid(QueryGrid(other, RigGeometry(f.rig).left), "jppc", 5'000);
  f.bus.publish(channels::kObstaclesStereo, wrong_grid);
  f.drain();
  EXPECT_EQ(f.heartbeat.bad_input_count(), 4);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find("does not match the configured grid"), std::string::npos);

  const uint8_t garbage[12] = {0};
  f.bus.publish_raw(channels::kDepthImage, garbage, sizeof(garbage));
  f.drain();
  EXPECT_EQ(f.heartbeat.bad_input_count(), 5);

  // The header of the configured grid, its cells 1 cm further on: refused on arrival (the labelling,
  // once its depth frame came, aborted the process)
  obstacle_grid_t moved = make_obstacle_grid(f.grid, "jppc", 6'000);
  for (float& x : moved.x) x += 0.01f;
  f.bus.publish(channels::kObstaclesStereo, moved);
  f.drain();
  f.send_depth(6'000, ground);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 6);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find("cell 0 is at"), std::string::npos);

  obstacle_grid_t bad_state = make_obstacle_grid(f.grid, "jppc", 7'000);
  bad_state.state[4] = 42;  // was labelled as an obstacle
  f.bus.publish(channels::kObstaclesStereo, bad_state);
  f.drain();
  f.send_depth(7'000, ground);
  EXPECT_EQ(f.heartbeat.bad_input_count(), 7);
  EXPECT_NE(f.heartbeat.snapshot().last_error.find("state 42"), std::string::npos);
  EXPECT_TRUE(f.labels.empty());

  // ...and it still works.
  f.send_depth(100'000, ground);
  f.send_stereo(100'000, 0);
  EXPECT_EQ(f.labels.size(), 1u);
}

// lcm-logplayer run twice into a running monitor: the second play's utimes
// go back to the first's; it used to be ignored as late and duplicate frames.
TEST(MonitorNode, ALogPlayedAgainIsLabelledAgain) {
  NodeFixture f;
  const cv::Mat ground = test::render_depth(f.rig, {});
  f.send_calibration();
  for (int play = 0; play < 2; ++play)
    for (int i = 0; i < 40; ++i) {  // 1.3 s at 30 Hz
      const int64_t t = 1'000'000 + i * 33'333;
      f.send_depth(t, ground);
      f.send_stereo(t, 0);
    }
  EXPECT_EQ(f.labels.size(), 80u);
  EXPECT_EQ(f.heartbeat.counter("clock_restarts"), 2);  // depth and stereo
  EXPECT_EQ(f.heartbeat.bad_input_count(), 0);
}

TEST(MonitorNode, UnmatchedStereoFramesAreCountedNotLabelled) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat ground = test::render_depth(f.rig, {});
  f.send_depth(0, ground);
  f.send_depth(200'000, ground);  // the depth stream skipped 5 frames
  f.send_stereo(100'000, 0);
  EXPECT_TRUE(f.labels.empty());
  f.heartbeat.tick();
  EXPECT_EQ(f.heartbeat.counter("stereo_unmatched"), 1);
}

// Two free-running 5 Hz streams out of phase: no stereo frame has a depth
// frame within the default 16.7 ms, and the monitor labelled nothing while
// saying "running". Said once the streams have not paired for 2 s; a pair
// ends it; frames decided at a stop say nothing of how the streams pair.
TEST(MonitorNode, StreamsThatNeverPairShowInTheStateUntilOnePairs) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat ground = test::render_depth(f.rig, {});
  for (int i = 1; i <= 11; ++i) {
    f.send_depth(i * 200'000, ground, i);
    f.send_stereo(i * 200'000 - 60'000, 0);  // 60 ms before its depth frame
    if (i == 10) {
      EXPECT_EQ(f.heartbeat.snapshot().state, "running") << "1.8 s unpaired: not yet said";
    }
  }
  EXPECT_TRUE(f.labels.empty());
  const std::string unpaired = "unpaired: no depth frame near the stereo frames";
  EXPECT_EQ(f.heartbeat.snapshot().state, unpaired);
  f.send_stereo(2'210'000, 0);  // near depth frame 11, but waits for a newer one
  f.node.flush();
  f.drain();
  ASSERT_EQ(f.labels.size(), 1u);
  EXPECT_EQ(f.heartbeat.snapshot().state, unpaired) << "a frame paired at a stop";
  f.send_depth(2'400'000, ground, 12);
  f.send_stereo(2'400'000, 0);
  ASSERT_EQ(f.labels.size(), 2u);
  EXPECT_EQ(f.heartbeat.snapshot().state, "running");
}

// A depth camera slower than the stereo one on the same clock pairs one
// stereo frame of every six: labels at its rate, not a stream unpaired.
TEST(MonitorNode, ASlowerDepthCameraIsNotUnpaired) {
  NodeFixture f;
  f.send_calibration();
  const cv::Mat ground = test::render_depth(f.rig, {});
  for (int k = 0; k <= 90; ++k) {  // 3 s of 30 Hz stereo, 5 Hz depth
    if (k % 6 == 0) f.send_depth(k * 33'333, ground, k / 6);
    f.send_stereo(k * 33'333, 0);
    ASSERT_EQ(f.heartbeat.snapshot().state, "running") << "stereo frame " << k;
  }
  EXPECT_EQ(f.labels.size(), 16u);
}

}  // namespace
}  // namespace ivoa
