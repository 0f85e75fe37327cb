// Matching a frame's messages by utime: the newest frame with every active
// part is drawn; parts nobody publishes are not waited for; a lagging part
// is waited for at most settle_ms; late parts and old frames are counted.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "ivoa/viewer/frame_matcher.hpp"
#include "viewer_messages.hpp"

namespace ivoa::viewer {
namespace {

using namespace test;

MatcherOptions options() {
  MatcherOptions o;
  o.max_frames = 8;
  o.active_ms = 3000;
  o.settle_ms = 500;
  return o;
}

TEST(ViewerFrameMatcher, ImagesAloneAreDrawnAtOnce) {
  FrameMatcher m(options());
  m.add_image(100, gray_image(100), 0);
  const auto f = m.take(1);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 100);
  EXPECT_EQ(f->part_count(), 1);
  EXPECT_FALSE(m.take(2)) << "nothing new";
}

TEST(ViewerFrameMatcher, WaitsForEveryActivePartThenTakesTheNewestCompleteFrame) {
  FrameMatcher m(options());
  // Frame 100 complete with a grid and introspection: both become active.
  m.add_image(100, gray_image(100), 0);
  m.add_stereo_grid(grid(100, {0}), 1);
  m.add_introspection(introspection(100), 2);
  ASSERT_EQ(m.take(3)->utime, 100);
  // Frames 200 and 300 arrive; introspection only for 200 so far.
  m.add_image(200, gray_image(200), 10);
  m.add_stereo_grid(grid(200, {0}), 11);
  m.add_image(300, gray_image(300), 20);
  m.add_stereo_grid(grid(300, {0}), 21);
  EXPECT_FALSE(m.take(22)) << "introspection is active: no frame is complete yet";
  m.add_introspection(introspection(200), 30);
  auto f = m.take(31);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 200);
  EXPECT_TRUE(f->introspection && f->stereo);
  m.add_introspection(introspection(300), 40);
  EXPECT_EQ(m.take(41)->utime, 300);
  EXPECT_EQ(m.skipped(), 0u);
}

TEST(ViewerFrameMatcher, NewerCompleteFrameSkipsOlderOnes) {
  FrameMatcher m(options());
  for (int64_t t : {100, 200, 300}) {
    m.add_image(t, gray_image(t), static_cast<double>(t) / 10);
    m.add_labels(labels(t, {0}), static_cast<double>(t) / 10);
  }
  m.add_image(400, gray_image(400), 41);  // labels for 400 not yet here
  const auto f = m.take(42);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 300);
  EXPECT_EQ(m.skipped(), 2u) << "frames 100 and 200 were never drawn";
  m.add_labels(labels(200, {0}), 43);
  EXPECT_EQ(m.late(), 1u) << "labels for a frame older than the one drawn";
  EXPECT_EQ(m.pending(), 1u) << "only frame 400 waits";
}

TEST(ViewerFrameMatcher, ALaggingPartIsWaitedForAtMostTheSettleTime) {
  FrameMatcher m(options());
  m.add_image(100, gray_image(100), 0);
  m.add_stereo_grid(grid(100, {0}), 0);
  m.add_introspection(introspection(100), 0);
  ASSERT_TRUE(m.take(1));
  m.add_image(200, gray_image(200), 100);
  m.add_stereo_grid(grid(200, {0}), 110);
  m.add_image(300, gray_image(300), 200);
  EXPECT_FALSE(m.take(300)) << "before settle_ms: wait for the introspection";
  const auto f = m.take(700);
  ASSERT_TRUE(f) << "after settle_ms: draw what there is";
  EXPECT_EQ(f->utime, 200) << "the frame with the most parts";
  EXPECT_FALSE(f->introspection);
}

TEST(ViewerFrameMatcher, PartsNotSeenRecentlyAreNotWaitedFor) {
  FrameMatcher m(options());
  m.add_image(100, gray_image(100), 0);
  m.add_introspection(introspection(100), 0);
  ASSERT_TRUE(m.take(1));
  // The introspection process stopped: after active_ms it is no longer expected.
  m.add_image(200, gray_image(200), 5000);
  m.add_stereo_grid(grid(200, {0}), 5001);
  const auto f = m.take(5002);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 200);
}

TEST(ViewerFrameMatcher, KeepsABoundedNumberOfFramesAndFlushes) {
  FrameMatcher m(options());
  m.add_image(1, gray_image(1), 0);
  m.add_introspection(introspection(1), 0);
  ASSERT_TRUE(m.take(0));
  for (int64_t t = 10; t < 30; ++t) m.add_image(t, gray_image(t), 1);  // introspection never comes
  EXPECT_EQ(m.pending(), 8u);
  EXPECT_EQ(m.skipped(), 12u);
  EXPECT_FALSE(m.take(2));
  const auto f = m.take(3, true);
  ASSERT_TRUE(f) << "flush draws the best there is without waiting";
  EXPECT_EQ(f->utime, 29);
  EXPECT_EQ(m.skipped(), 19u);
}

TEST(ViewerFrameMatcher, EveryFrameModeHandsOutFramesInOrder) {
  MatcherOptions o = options();
  o.every_frame = true;
  FrameMatcher m(o);
  // As a log plays: frame 100's introspection never came (the live process
  // skipped it); frame 200 is complete.
  m.add_image(100, gray_image(100), 0);
  m.add_stereo_grid(grid(100, {0}), 0);
  m.add_image(200, gray_image(200), 1);
  m.add_stereo_grid(grid(200, {0}), 1);
  m.add_introspection(introspection(200), 2);
  m.add_image(300, gray_image(300), 3);
  auto f = m.take(4);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 100) << "a newer complete frame means this one's parts are all in";
  EXPECT_FALSE(f->introspection);
  EXPECT_EQ(m.take(4)->utime, 200);
  EXPECT_FALSE(m.take(4)) << "frame 300 may still get its parts";
  EXPECT_EQ(m.take(5, true)->utime, 300);
  EXPECT_EQ(m.skipped(), 0u);
}

TEST(ViewerFrameMatcher, ALogsFirstFramesWaitForAPartNotSeenYet) {
  MatcherOptions o = options();
  o.every_frame = true;
  o.expected[kIntrospection] = true;  // the log holds introspection, but its first answer comes late
  FrameMatcher m(o);
  m.add_image(100, gray_image(100), 0);
  m.add_stereo_grid(grid(100, {0}), 0);
  m.add_image(200, gray_image(200), 1);
  m.add_stereo_grid(grid(200, {0}), 1);
  EXPECT_FALSE(m.take(2)) << "no introspection has come yet, but the log has some";
  m.add_introspection(introspection(100), 3);
  auto f = m.take(4);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->utime, 100);
  EXPECT_TRUE(f->introspection) << "drawn with its introspection, not before it";
  EXPECT_FALSE(m.take(5)) << "frame 200 waits for its own";

  FrameMatcher unexpected(options());  // live: a part never seen is not waited for
  unexpected.add_image(100, gray_image(100), 0);
  unexpected.add_stereo_grid(grid(100, {0}), 0);
  EXPECT_EQ(unexpected.take(1)->utime, 100);
}

TEST(ViewerFrameMatcher, EveryFrameModeDrawsTheOldestIncompleteFrameRatherThanDropIt) {
  MatcherOptions o = options();
  o.every_frame = true;
  o.expected[kIntrospection] = true;
  FrameMatcher m(o);
  std::vector<int64_t> drawn;
  for (int64_t t = 1; t <= 20; ++t) {  // introspection never comes; frames arrive faster than settle_ms
    m.add_image(t, gray_image(t), 0);
    while (auto f = m.take(1)) drawn.push_back(f->utime);
  }
  EXPECT_EQ(drawn.size(), 12u) << "the oldest, once more than max_frames (8) wait";
  while (auto f = m.take(2, true)) drawn.push_back(f->utime);
  ASSERT_EQ(drawn.size(), 20u);
  for (size_t i = 0; i < drawn.size(); ++i) EXPECT_EQ(drawn[i], static_cast<int64_t>(i + 1));
  EXPECT_EQ(m.skipped(), 0u);
}

// One frame stamped far ahead stopped the drawing for good; a log played
// again drew nothing the second time.
TEST(ViewerFrameMatcher, AClockThatWentBackIsFollowed) {
  FrameMatcher m(options());
  m.add_image(100, gray_image(100), 0);
  ASSERT_EQ(m.take(1)->utime, 100);
  m.add_image(1'000'000'000'100, gray_image(100), 2);  // 11.6 days ahead
  ASSERT_EQ(m.take(3)->utime, 1'000'000'000'100);
  m.add_image(200, gray_image(100), 4);
  ASSERT_TRUE(m.take(5)) << "the frame after the jump";
  EXPECT_EQ(m.clock_restarts(), 1u);
  m.add_image(150, gray_image(100), 6);  // a part a little late is still late
  EXPECT_FALSE(m.take(7));
  EXPECT_EQ(m.late(), 1u);
  m.add_image(INT64_MIN, gray_image(100), 8);  // of any sign
  EXPECT_EQ(m.take(9)->utime, INT64_MIN);
}

TEST(ViewerFrameMatcher, OverlaysWithoutTheirImageAreNotDrawn) {
  FrameMatcher m(options());
  m.add_stereo_grid(grid(100, {0}), 0);
  EXPECT_FALSE(m.take(1000, true));
}

}  // namespace
}  // namespace ivoa::viewer
