// The stereo detector process's node, in process on memq://: frames before a
// calibration, grids out with the source utime, bad input counted and
// skipped, a changed calibration picked up.
#include <gtest/gtest.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/process_status_t.hpp"
#include "stereo_detector_node.hpp"
#include "synthetic_scene.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

int64_t counter(const process_status_t& s, const std::string& name) {
  for (size_t i = 0; i < s.counter_names.size(); ++i)
    if (s.counter_names[i] == name) return s.counter_values[i];
  return -1;
}

class StereoDetectorNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    test::SyntheticScene room;
    room.boxes.push_back({{4.0, -4.0, 0.0}, {4.2, 4.0, 2.5}, true, 140, 9, 3.0});
    test::render_pair(room, rig_, left_, right_, 1);
    bus_.subscribe<obstacle_grid_t>("OBSTACLES_STEREO",
                                    [this](const obstacle_grid_t& m, const ReceiveInfo&) { grids_.push_back(m); });
  }

  // Bounded: handles the bus until `done` or ~5 s.
  template <class Pred>
  bool handle_until(Pred done) {
    for (int i = 0; i < 250 && !done(); ++i) bus_.handle(20);
    return done();
  }

  void publish_frame(int64_t utime, const cv::Mat& left, const cv::Mat& right) {
    stereo_image_t msg;
    msg.utime = utime;
    msg.seq = utime;
    msg.source = "test";
    msg.left = encode_image(left, image_t::PIXEL_FORMAT_BGR, utime);
    msg.right = encode_image(right, image_t::PIXEL_FORMAT_BGR, utime);
    ASSERT_TRUE(bus_.publish("STEREO_IMAGES", msg));
  }
  void publish_frame(int64_t utime) { publish_frame(utime, left_, right_); }
  void publish_calibration(const RigCalibration& rig) {
    rig_calibration_t msg = to_message(rig, 1);
    ASSERT_TRUE(bus_.publish("RIG_CALIBRATION", msg));
  }
  bool grid_arrived(int64_t utime) {
    return handle_until([&] { return !grids_.empty() && grids_.back().utime == utime; });
  }

  StereoDetectorOptions options_;
  RigCalibration rig_ = test::make_test_rig(15.0);
  cv::Mat left_, right_;
  Bus bus_{"memq://"};
  Heartbeat heartbeat_{bus_, "stereo_detector_test"};
  std::vector<obstacle_grid_t> grids_;
};

TEST_F(StereoDetectorNodeTest, PublishesAGridPerFrameOnceCalibrated) {
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.start();
  publish_frame(100);
  ASSERT_TRUE(handle_until([&] { return counter(heartbeat_.snapshot(), node.kFramesWithoutCalibration) == 1; }));
  EXPECT_EQ(heartbeat_.snapshot().state, "waiting for calibration");
  EXPECT_TRUE(grids_.empty());

  publish_calibration(rig_);
  publish_frame(200);
  ASSERT_TRUE(grid_arrived(200));
  const obstacle_grid_t& grid = grids_.back();
  EXPECT_EQ(grid.detector, "jppc");
  EXPECT_EQ(grid.num_cells, 11 * 13);
  EXPECT_GT(grid.compute_ms, 0.0);
  int free = 0, obstacle = 0;
  for (int8_t s : grid.state) {
    free += s == obstacle_grid_t::STATE_FREE;
    obstacle += s == obstacle_grid_t::STATE_OBSTACLE;
  }
  EXPECT_GT(free, 60);  // an empty room
  EXPECT_EQ(obstacle, 0);
  // The worker counts a grid just after publishing it.
  ASSERT_TRUE(handle_until([&] { return heartbeat_.snapshot().messages_out == 1; }));
  const process_status_t status = heartbeat_.snapshot();
  EXPECT_EQ(status.state, "running");
  EXPECT_EQ(status.messages_in, 2);
  EXPECT_EQ(status.messages_out, 1);
  EXPECT_EQ(status.bad_input, 0);
  EXPECT_EQ(counter(status, node.kCalibrationsApplied), 1);
}

// Frames that arrive faster than the detector works through them (a
// simulator rendering ahead) are all held, and processed in order.
TEST_F(StereoDetectorNodeTest, WithAQueueEveryFrameOfABurstGetsItsGrid) {
  options_.queue_frames = 6;
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.start();
  publish_calibration(rig_);
  for (int64_t utime = 1; utime <= 6; ++utime) publish_frame(utime);
  ASSERT_TRUE(handle_until([&] { return grids_.size() == 6; }));
  for (size_t i = 0; i < grids_.size(); ++i) EXPECT_EQ(grids_[i].utime, static_cast<int64_t>(i) + 1);
  EXPECT_EQ(heartbeat_.snapshot().dropped, 0);
}

// Stopped with a queue still full (the end of a recording played fast),
// the node labels the frames it holds before it exits; past --max-frames
// they are counted as dropped. Every frame in is out or dropped.
TEST_F(StereoDetectorNodeTest, StopFinishesTheQueuedFramesFirst) {
  options_.queue_frames = 6;
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.set_calibration(rig_);
  node.start();
  for (int64_t utime = 1; utime <= 6; ++utime) publish_frame(utime);
  for (int i = 0; i < 6; ++i) bus_.handle(5);
  node.stop();
  const process_status_t s = heartbeat_.snapshot();
  EXPECT_EQ(s.messages_in, 6);
  EXPECT_EQ(s.messages_out, 6);
  EXPECT_EQ(s.dropped, 0);
  ASSERT_TRUE(handle_until([&] { return grids_.size() == 6; }));
  EXPECT_EQ(grids_.back().utime, 6);
}

TEST_F(StereoDetectorNodeTest, FramesQueuedPastMaxFramesAreCountedAsDropped) {
  options_.queue_frames = 6;
  options_.max_frames = 2;
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.set_calibration(rig_);
  node.start();
  for (int64_t utime = 1; utime <= 5; ++utime) publish_frame(utime);
  for (int i = 0; i < 5; ++i) bus_.handle(5);
  node.stop();
  const process_status_t s = heartbeat_.snapshot();
  EXPECT_TRUE(node.finished());
  EXPECT_EQ(s.messages_out, 2);
  EXPECT_EQ(s.dropped, 3);
}

// Frames the kernel dropped while the process stalled never reach it: the
// gaps in their seq are counted, so the loss shows in the heartbeat. A seq
// that goes back (the driver restarted) starts the count again.
TEST_F(StereoDetectorNodeTest, FramesThatNeverArrivedAreCountedFromTheSeqGaps) {
  options_.queue_frames = 8;
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.start();
  publish_calibration(rig_);
  for (const int64_t seq : {1, 2, 5, 1, 3}) publish_frame(seq);
  ASSERT_TRUE(handle_until([&] { return grids_.size() == 5; }));
  EXPECT_EQ(heartbeat_.counter(kFramesMissed), 3) << "3 and 4, then 2 after the restart";
  EXPECT_EQ(heartbeat_.snapshot().dropped, 0) << "not dropped by the process: they never came";
}

TEST_F(StereoDetectorNodeTest, BadInputIsCountedAndSkipped) {
  bus_.on_decode_error([&](const std::string& what) { heartbeat_.bad_input(what); });
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.start();
  publish_calibration(rig_);
  const cv::Mat small(480, 640, CV_8UC3, cv::Scalar::all(50));
  publish_frame(10, small, small);
  ASSERT_TRUE(handle_until([&] { return heartbeat_.bad_input_count() == 1; }));
  EXPECT_NE(heartbeat_.snapshot().last_error.find("640x480"), std::string::npos);

  const uint8_t garbage[7] = {9, 8, 7, 6, 5, 4, 3};
  bus_.publish_raw("STEREO_IMAGES", garbage, sizeof(garbage));
  ASSERT_TRUE(handle_until([&] { return heartbeat_.bad_input_count() == 2; }));

  stereo_image_t broken;  // a JPEG that is not one
  broken.utime = 11;
  broken.left = encode_image(left_, image_t::PIXEL_FORMAT_BGR, 11);
  broken.left.pixelformat = image_t::PIXEL_FORMAT_JPEG;
  broken.right = broken.left;
  bus_.publish("STEREO_IMAGES", broken);
  ASSERT_TRUE(handle_until([&] { return heartbeat_.bad_input_count() == 3; }));

  rig_calibration_t invalid = to_message(rig_, 2);
  invalid.left.width = 0;
  bus_.publish("RIG_CALIBRATION", invalid);
  ASSERT_TRUE(handle_until([&] { return heartbeat_.bad_input_count() == 4; }));

  publish_frame(12);  // still running, with the valid calibration
  ASSERT_TRUE(grid_arrived(12));
  EXPECT_EQ(grids_.size(), 1u);
}

TEST_F(StereoDetectorNodeTest, AChangedCalibrationIsPickedUp) {
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.start();
  publish_calibration(rig_);
  publish_frame(1);
  ASSERT_TRUE(grid_arrived(1));
  publish_calibration(rig_);  // re-published unchanged (as at 1 Hz): no rebuild
  publish_frame(2);
  ASSERT_TRUE(grid_arrived(2));
  EXPECT_EQ(counter(heartbeat_.snapshot(), node.kCalibrationsApplied), 1);

  publish_calibration(test::make_test_rig(25.0));  // pitched further down: the ground rises in the image
  publish_frame(3);
  ASSERT_TRUE(grid_arrived(3));
  EXPECT_EQ(counter(heartbeat_.snapshot(), node.kCalibrationsApplied), 2);
  const size_t centre = static_cast<size_t>(5 * 13 + 6);  // x = 1.75, y = 0
  EXPECT_LT(grids_[2].v[centre], grids_[1].v[centre] - 50);
}

TEST_F(StereoDetectorNodeTest, DenseModelAndMaxFrames) {
  options_.model = "dense";
  options_.max_frames = 2;
  StereoDetectorNode node(bus_, heartbeat_, options_);
  node.set_calibration(rig_);  // as from --calibration FILE
  node.start();
  publish_frame(1);
  ASSERT_TRUE(grid_arrived(1));
  EXPECT_FALSE(node.finished());
  EXPECT_EQ(grids_.back().detector, "dense");
  publish_frame(2);
  ASSERT_TRUE(grid_arrived(2));
  ASSERT_TRUE(handle_until([&] { return node.finished(); }));
}

}  // namespace
}  // namespace ivoa
