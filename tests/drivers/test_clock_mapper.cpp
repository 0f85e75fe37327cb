#include <gtest/gtest.h>

#include "ivoa/aravis_stereo/clock_mapper.hpp"

namespace ivoa::aravis_stereo {
namespace {

TEST(ClockMapper, RemovesReceiveJitterKeepingTheCamerasSpacing) {
  ClockMapper clock(8);
  const int64_t offset = 1'700'000'000'000'000;  // camera clock counts from power-up
  const int64_t delays[] = {3'000, 25'000, 2'000, 18'000, 2'500, 40'000};
  int64_t previous = 0;
  for (int i = 0; i < 6; ++i) {
    const int64_t device = 1'000'000 + i * 50'000;
    const int64_t mapped = clock.map(device, device + offset + delays[i]);
    // The least-delayed frame so far sets the offset; spacing is the camera's.
    if (i >= 2) {
      EXPECT_EQ(mapped, device + offset + 2'000) << "frame " << i;
    }
    if (i >= 3) {
      EXPECT_EQ(mapped - previous, 50'000) << "frame " << i;
    }
    previous = mapped;
  }
}

TEST(ClockMapper, ForgetsOldOffsetsOutsideTheWindowAndAfterReset) {
  ClockMapper clock(2);
  EXPECT_EQ(clock.map(100, 1'100), 1'100);  // offset 1000
  EXPECT_EQ(clock.map(200, 1'300), 1'200);  // offset 1100, min 1000
  EXPECT_EQ(clock.map(300, 1'450), 1'400);  // window {1100, 1150}
  clock.reset();
  EXPECT_EQ(clock.map(10, 5'000), 5'000);
}

TEST(ClockMapper, CameraWithoutTimestampsKeepsHostTime) {
  ClockMapper clock;
  EXPECT_EQ(clock.map(0, 123'456), 123'456);
}

}  // namespace
}  // namespace ivoa::aravis_stereo
