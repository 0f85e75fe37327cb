// The watch on an .oni recording's free disk space: it looks once a period,
// says "low" and "full" once each, and says nothing when the space cannot
// be read.
#include <gtest/gtest.h>

#include <optional>

#include "ivoa/openni2_kinect/recording_disk_watch.hpp"

namespace ivoa::openni2_kinect {
namespace {

using Event = RecordingDiskWatch::Event;

TEST(RecordingDiskWatch, SaysLowThenFullOnceEachAsTheDiskFills) {
  std::optional<uint64_t> free = 1000;
  int looks = 0;
  RecordingDiskWatch watch("/robot/rec/kinect.oni", {500, 10, 1.0}, [&] {
    ++looks;
    return free;
  });
  EXPECT_EQ(watch.check(0.0), Event::kNone);
  free = 400;
  EXPECT_EQ(watch.check(0.5), Event::kNone) << "looked again before its period";
  EXPECT_EQ(looks, 1);
  EXPECT_EQ(watch.check(1.0), Event::kLow);
  EXPECT_EQ(watch.check(2.0), Event::kNone) << "low is said once";
  free = 9;
  EXPECT_EQ(watch.check(3.0), Event::kFull);
  EXPECT_TRUE(watch.full());
  EXPECT_EQ(watch.last_free_bytes(), 9u);
  free = 1000;  // space freed by hand: what was dropped stays dropped
  EXPECT_EQ(watch.check(4.0), Event::kNone);
  EXPECT_TRUE(watch.full());
}

TEST(RecordingDiskWatch, ADiskThatFillsAtOnceIsFullNotLow) {
  std::optional<uint64_t> free = 1000;
  RecordingDiskWatch watch("kinect.oni", {500, 10, 1.0}, [&] { return free; });
  EXPECT_EQ(watch.check(0.0), Event::kNone);
  free = 0;
  EXPECT_EQ(watch.check(1.0), Event::kFull);
}

TEST(RecordingDiskWatch, SpaceThatCannotBeReadIsNoEvent) {
  RecordingDiskWatch watch("kinect.oni", {500, 10, 1.0}, [] { return std::optional<uint64_t>(); });
  EXPECT_EQ(watch.check(0.0), Event::kNone);
  EXPECT_FALSE(watch.full());
}

TEST(RecordingDiskWatch, ByDefaultReadsTheRecordingFoldersFileSystem) {
  RecordingDiskWatch watch("/tmp/kinect.oni", {1, 0, 1.0});
  EXPECT_EQ(watch.check(0.0), Event::kNone);
  EXPECT_GT(watch.last_free_bytes(), 0u) << "/tmp has no free space?";
}

}  // namespace
}  // namespace ivoa::openni2_kinect
