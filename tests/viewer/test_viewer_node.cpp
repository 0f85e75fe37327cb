// The viewer node on an in-memory bus: a frame's five messages make one
// figure file; malformed introspection is counted as bad input, not drawn;
// without a display no window is tried.
#include <cstdlib>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/stereo_image_t.hpp"
#include "ivoa/viewer/viewer_node.hpp"
#include "test_rig.hpp"
#include "viewer_messages.hpp"

namespace ivoa::viewer {
namespace {

using namespace test;

void publish_frame(Bus& bus, int64_t utime, bool with_introspection = true) {
  stereo_image_t pair{};
  pair.utime = utime;
  pair.source = "test";
  pair.left = gray_image(utime);
  pair.right = gray_image(utime);
  bus.publish("STEREO_IMAGES", pair);
  auto stereo = grid(utime, {1, 0, 0, 1});
  auto depth = grid(utime, {0, 0, 1, 1}, "depth_monitor");
  auto l = labels(utime, {2, 1, 3, 0});
  bus.publish("OBSTACLES_STEREO", stereo);
  bus.publish("OBSTACLES_DEPTH", depth);
  bus.publish("INTROSPECTION_LABELS", l);
  if (with_introspection) {
    auto h = introspection(utime, {2, 1, 3, 0});
    bus.publish("INTROSPECTION", h);
  }
}

void handle_all(Bus& bus) {
  while (bus.handle(20) > 0) {
  }
}

TEST(ViewerNode, DrawsAFigureFileFromAFramesMessages) {
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.output.out_dir = dir.path().string();
  ViewerNode node(bus, heartbeat, o);
  publish_frame(bus, 1000);
  handle_all(bus);
  node.tick();
  node.finish();
  EXPECT_EQ(node.figures(), 1);
  EXPECT_TRUE(std::filesystem::exists(dir.file("frame_1000.png")));
  const auto status = heartbeat.snapshot();
  EXPECT_EQ(status.messages_in, 5);
  EXPECT_EQ(status.messages_out, 1);
  EXPECT_EQ(status.bad_input, 0);
}

TEST(ViewerNode, MalformedIntrospectionIsCountedAndTheRestDrawn) {
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.output.out_dir = dir.path().string();
  ViewerNode node(bus, heartbeat, o);
  publish_frame(bus, 2000, false);
  auto bad = introspection(2000);
  bad.rows = 3;  // rows * cols != num_cells
  bus.publish("INTROSPECTION", bad);
  handle_all(bus);
  node.finish();
  EXPECT_EQ(heartbeat.bad_input_count(), 1);
  EXPECT_EQ(node.figures(), 1);
  EXPECT_NE(heartbeat.snapshot().last_error.find("INTROSPECTION utime 2000: heatmap 3x16 is not its 160 cells"),
            std::string::npos)
      << heartbeat.snapshot().last_error;
}

// Values no model gives were drawn as if valid: NaN probabilities as a solid
// "certainly fine" blue, label 9 and state 7 in grey. Each such message is
// bad input now, named, and the frame drawn without it.
TEST(ViewerNode, ContentNoProcessGivesIsCountedNotDrawn) {
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.output.out_dir = dir.path().string();
  ViewerNode node(bus, heartbeat, o);
  publish_frame(bus, 3000, false);
  auto nan_heatmap = introspection(3000);
  nan_heatmap.prob_fp[5] = std::numeric_limits<float>::quiet_NaN();
  bus.publish("INTROSPECTION", nan_heatmap);
  auto bad_label = labels(3000, {1, 1, 1, 1});
  bad_label.label[2] = 9;
  bus.publish("INTROSPECTION_LABELS", bad_label);
  auto bad_state = grid(3000, {0, 7, 0, 0});
  bus.publish("OBSTACLES_STEREO", bad_state);
  handle_all(bus);
  node.finish();
  EXPECT_EQ(heartbeat.bad_input_count(), 3);
  EXPECT_EQ(node.figures(), 1);
  const std::string error = heartbeat.snapshot().last_error;
  EXPECT_NE(error.find("OBSTACLES_STEREO utime 3000: cell 1: state 7 is none of"), std::string::npos) << error;
}

TEST(ViewerNode, UndecodableImageIsBadInput) {
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.output.out_dir = dir.path().string();
  ViewerNode node(bus, heartbeat, o);
  stereo_image_t pair{};
  pair.utime = 5;
  pair.left = gray_image(5);
  pair.left.data.resize(10);  // truncated pixels
  pair.right = pair.left;
  bus.publish("STEREO_IMAGES", pair);
  handle_all(bus);
  node.finish();
  EXPECT_EQ(node.figures(), 0);
  EXPECT_EQ(heartbeat.bad_input_count(), 1);
}

TEST(ViewerNode, EveryFrameModeDrawsEachFrameOfALog) {
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.every_frame = true;
  o.output.out_dir = dir.path().string();
  o.output.max_images = 0;
  ViewerNode node(bus, heartbeat, o);
  // Published back to back, as a log read at full speed.
  for (int64_t t = 1; t <= 5; ++t) publish_frame(bus, t * 100, t != 3);
  handle_all(bus);
  node.tick();
  node.finish();
  EXPECT_EQ(node.figures(), 5);
  EXPECT_EQ(heartbeat.snapshot().dropped, 0);
}

TEST(ViewerNode, NoWindowWithoutADisplayButFilesStillWritten) {
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display ? display : "";
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  std::string why;
  EXPECT_FALSE(window_possible(&why));
  EXPECT_FALSE(why.empty());
  ivoa::test::TempDir dir;
  Bus bus("memq://");
  Heartbeat heartbeat(bus, "viewer", "VIEWER_TEST_STATUS", 3600);
  ViewerOptions o;
  o.window = true;
  o.output.out_dir = dir.path().string();
  ViewerNode node(bus, heartbeat, o);
  publish_frame(bus, 3000);
  handle_all(bus);
  node.tick();
  node.finish();
  EXPECT_FALSE(node.window_shown());
  EXPECT_EQ(node.figures(), 1);
  EXPECT_TRUE(std::filesystem::exists(dir.file("frame_3000.png")));
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
}

}  // namespace
}  // namespace ivoa::viewer
