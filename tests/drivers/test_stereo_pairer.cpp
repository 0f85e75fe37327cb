// Pairing left/right frames by timestamp: never by arrival order, drops
// and out-of-order frames counted, 16-bit GigE frame ids that wrap.
#include <gtest/gtest.h>

#include "ivoa/aravis_stereo/frame_id_tracker.hpp"
#include "ivoa/aravis_stereo/stereo_pairer.hpp"

namespace ivoa::aravis_stereo {
namespace {

CameraFrame frame(Side side, int64_t time_us, uint64_t id) {
  CameraFrame f;
  f.side = side;
  f.pairing_time_us = time_us;
  f.utime = 1'700'000'000'000'000 + time_us;
  f.frame_id = id;
  return f;
}

constexpr int64_t kPeriod = 33'333;  // 30 Hz

PairingOptions options(int64_t tolerance_us = kPeriod / 2, size_t max_pending = 4) {
  PairingOptions o;
  o.tolerance_us = tolerance_us;
  o.max_pending = max_pending;
  return o;
}

TEST(StereoPairer, PairsFramesThatArriveTogether) {
  StereoPairer pairer(options());
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, 0, 1)));
  auto pair = pairer.add(frame(Side::kRight, 1'500, 7));
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->left.frame_id, 1u);
  EXPECT_EQ(pair->right.frame_id, 7u);
  EXPECT_EQ(pair->skew_us(), 1'500);
  EXPECT_EQ(pairer.counts().pairs, 1);
  EXPECT_EQ(pairer.counts().unpaired, 0);
}

TEST(StereoPairer, PairsByTimestampNotArrivalOrder) {
  // The left stream had three frames queued before the right one delivered
  // anything: pairing the n-th arrival of each side would be 1-2 periods off.
  StereoPairer pairer(options());
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(pairer.add(frame(Side::kLeft, i * kPeriod, 10 + i)));
  std::vector<std::pair<uint64_t, uint64_t>> pairs;
  for (int i = 0; i < 3; ++i) {
    auto pair = pairer.add(frame(Side::kRight, i * kPeriod + 800, 20 + i));
    ASSERT_TRUE(pair) << "right frame " << i;
    pairs.emplace_back(pair->left.frame_id, pair->right.frame_id);
    EXPECT_LE(std::llabs(pair->skew_us()), 800);
  }
  EXPECT_EQ(pairs, (std::vector<std::pair<uint64_t, uint64_t>>{{10, 20}, {11, 21}, {12, 22}}));
}

TEST(StereoPairer, LateRightFrameDoesNotPairWithTheWrongLeft) {
  // Right frame 1 is lost; right frame 2 must pair with left 2, and left 1
  // is dropped as unpaired.
  StereoPairer pairer(options());
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, 0, 1)));
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, kPeriod, 2)));
  auto pair = pairer.add(frame(Side::kRight, kPeriod + 300, 102));
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->left.frame_id, 2u);
  EXPECT_EQ(pairer.counts().unpaired, 1);
  EXPECT_EQ(pairer.pending(Side::kLeft), 0u);
}

TEST(StereoPairer, NeverPairsFramesFurtherApartThanTheTolerance) {
  StereoPairer pairer(options(5'000));
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, 0, 1)));
  EXPECT_FALSE(pairer.add(frame(Side::kRight, 12'000, 1)));
  EXPECT_EQ(pairer.counts().pairs, 0);
  EXPECT_EQ(pairer.pending(Side::kLeft), 1u);
  EXPECT_EQ(pairer.pending(Side::kRight), 1u);
}

TEST(StereoPairer, OneCameraSilentKeepsAtMostMaxPendingFrames) {
  StereoPairer pairer(options(kPeriod / 2, 3));
  for (int i = 0; i < 10; ++i) EXPECT_FALSE(pairer.add(frame(Side::kLeft, i * kPeriod, i + 1)));
  EXPECT_EQ(pairer.pending(Side::kLeft), 3u);
  EXPECT_EQ(pairer.counts().unpaired, 7);
  // The right camera comes back: it pairs with the newest left frame it matches.
  auto pair = pairer.add(frame(Side::kRight, 9 * kPeriod + 100, 50));
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->left.frame_id, 10u);
  EXPECT_EQ(pairer.counts().unpaired, 9);  // the two older pending left frames
}

TEST(StereoPairer, OutOfOrderFramesWaitingForAPartnerStillPair) {
  StereoPairer pairer(options());
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, kPeriod, 2)));  // arrives first
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, 0, 1)));        // the older one, late
  auto first = pairer.add(frame(Side::kRight, 200, 1));
  auto second = pairer.add(frame(Side::kRight, kPeriod + 200, 2));
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->left.frame_id, 1u);
  EXPECT_EQ(second->left.frame_id, 2u);
  EXPECT_EQ(pairer.counts().out_of_order, 0);
}

TEST(StereoPairer, FrameOlderThanThePublishedPairIsDroppedAsOutOfOrder) {
  StereoPairer pairer(options());
  pairer.add(frame(Side::kLeft, kPeriod, 2));
  ASSERT_TRUE(pairer.add(frame(Side::kRight, kPeriod, 2)));
  // Publishing these would make utime go backwards downstream.
  EXPECT_FALSE(pairer.add(frame(Side::kLeft, 0, 1)));
  EXPECT_FALSE(pairer.add(frame(Side::kRight, 0, 1)));
  EXPECT_EQ(pairer.counts().out_of_order, 2);
  EXPECT_EQ(pairer.pending(Side::kLeft) + pairer.pending(Side::kRight), 0u);
}

TEST(StereoPairer, PairsAcrossThe16BitFrameIdWrapWithoutCountingMissedFrames) {
  StereoPairer pairer(options());
  const uint64_t ids[] = {65533, 65534, 65535, 1, 2, 3};
  for (int i = 0; i < 6; ++i) {
    pairer.add(frame(Side::kLeft, i * kPeriod, ids[i]));
    ASSERT_TRUE(pairer.add(frame(Side::kRight, i * kPeriod + 100, ids[i]))) << "frame " << ids[i];
  }
  EXPECT_EQ(pairer.counts().pairs, 6);
  EXPECT_EQ(pairer.counts().missed[0], 0);
  EXPECT_EQ(pairer.counts().missed[1], 0);
}

TEST(StereoPairer, CountsFramesMissingFromTheCameraAcrossTheWrap) {
  StereoPairer pairer(options());
  pairer.add(frame(Side::kLeft, 0, 65534));
  pairer.add(frame(Side::kLeft, 3 * kPeriod, 2));  // 65535 and 1 never arrived
  EXPECT_EQ(pairer.counts().missed[0], 2);
}

TEST(StereoPairer, ResetForgetsAReconnectedCamerasClockAndCounter) {
  StereoPairer pairer(options());
  pairer.add(frame(Side::kRight, 10 * kPeriod, 500));
  pairer.add(frame(Side::kLeft, 10 * kPeriod, 500));
  pairer.add(frame(Side::kRight, 11 * kPeriod, 501));
  pairer.reset(Side::kRight);  // its pending frame is dropped
  EXPECT_EQ(pairer.counts().unpaired, 1);
  // A device clock that restarted near zero is not "out of order" after a reset.
  pairer.add(frame(Side::kRight, 100, 65400));
  EXPECT_EQ(pairer.counts().out_of_order, 0);
  EXPECT_EQ(pairer.counts().missed[1], 0);
}

TEST(FrameIdTracker, Counts16BitGapsAndSkipsZero) {
  FrameIdTracker ids;
  EXPECT_EQ(ids.observe(65534).kind, FrameIdTracker::Kind::kFirst);
  auto step = ids.observe(65535);
  EXPECT_EQ(step.kind, FrameIdTracker::Kind::kNext);
  EXPECT_EQ(step.missed, 0);
  step = ids.observe(1);  // 0 is never used by GigE Vision
  EXPECT_EQ(step.kind, FrameIdTracker::Kind::kNext);
  EXPECT_EQ(step.missed, 0);
  step = ids.observe(5);
  EXPECT_EQ(step.missed, 3);
}

TEST(FrameIdTracker, ReportsBackwardsAndRepeatedIds) {
  FrameIdTracker ids;
  ids.observe(10);
  ids.observe(11);
  EXPECT_EQ(ids.observe(11).kind, FrameIdTracker::Kind::kBackwards);
  EXPECT_EQ(ids.observe(9).kind, FrameIdTracker::Kind::kBackwards);
  // 65535 just before 2 (across the wrap) is behind, not 65532 frames ahead.
  ids.reset();
  ids.observe(2);
  EXPECT_EQ(ids.observe(65535).kind, FrameIdTracker::Kind::kBackwards);
  EXPECT_EQ(ids.observe(3).missed, 0);
}

TEST(FrameIdTracker, WideIdsDoNotWrapAt16Bits) {
  FrameIdTracker ids;
  ids.observe(70'000);
  const auto step = ids.observe(70'005);
  EXPECT_EQ(step.kind, FrameIdTracker::Kind::kNext);
  EXPECT_EQ(step.missed, 4);
}

}  // namespace
}  // namespace ivoa::aravis_stereo

namespace ivoa::aravis_stereo {
namespace {

// Three pairs with right id = left id + 100 lock the offset.
void lock_with_offset_100(StereoPairer& pairer) {
  for (int i = 0; i < 3; ++i) {
    pairer.add(frame(Side::kLeft, i * kPeriod, 1 + i));
    ASSERT_TRUE(pairer.add(frame(Side::kRight, i * kPeriod + 500, 101 + i)));
  }
  ASSERT_TRUE(pairer.locked());
}

TEST(StereoPairerLock, ALateFrameCannotPairWithItsNeighboursPartner) {
  // Right frame 3 reaches the host 0.6 periods late: by time alone it is
  // nearer left frame 4 than left frame 3.
  const int64_t late = 3 * kPeriod + 6 * kPeriod / 10;
  {
    PairingOptions time_only = options();
    time_only.lock_after_pairs = 0;
    StereoPairer pairer(time_only);
    for (int i = 0; i < 3; ++i) {
      pairer.add(frame(Side::kLeft, i * kPeriod, 1 + i));
      pairer.add(frame(Side::kRight, i * kPeriod + 500, 101 + i));
    }
    pairer.add(frame(Side::kLeft, 3 * kPeriod, 4));
    pairer.add(frame(Side::kLeft, 4 * kPeriod, 5));
    auto wrong = pairer.add(frame(Side::kRight, late, 104));
    ASSERT_TRUE(wrong) << "time-only pairing takes the neighbour";
    EXPECT_EQ(wrong->left.frame_id, 5u);
  }
  StereoPairer pairer(options());
  lock_with_offset_100(pairer);
  pairer.add(frame(Side::kLeft, 3 * kPeriod, 4));
  pairer.add(frame(Side::kLeft, 4 * kPeriod, 5));
  EXPECT_FALSE(pairer.add(frame(Side::kRight, late, 104))) << "its numbered partner is too far in time: no pair";
  auto next = pairer.add(frame(Side::kRight, 4 * kPeriod + 500, 105));
  ASSERT_TRUE(next);
  EXPECT_EQ(next->left.frame_id, 5u);
  EXPECT_EQ(next->right.frame_id, 105u);
  EXPECT_TRUE(pairer.locked());
}

TEST(StereoPairerLock, SurvivesLostFramesAndThe16BitWrap) {
  StereoPairer pairer(options());
  // Right ids wrap from 65535 to 1 while the left ids do not.
  const uint64_t right_ids[] = {65533, 65534, 65535, 1, 2, 3, 4};
  for (int i = 0; i < 7; ++i) {
    if (i == 4) continue;  // left frame 4 incomplete: never delivered
    pairer.add(frame(Side::kLeft, i * kPeriod, 1000 + i));
    auto pair = pairer.add(frame(Side::kRight, i * kPeriod + 300, right_ids[i]));
    if (i != 4) {
      ASSERT_TRUE(pair) << "frame " << i;
      EXPECT_EQ(pair->left.frame_id, 1000u + i);
    }
  }
  EXPECT_TRUE(pairer.locked());
  EXPECT_EQ(pairer.counts().missed[0], 1);
  EXPECT_EQ(pairer.counts().missed[1], 1);
  EXPECT_EQ(pairer.counts().unlocks, 0);
}

TEST(StereoPairerLock, DriftingCamerasUnlockAndPairByTimeAgain) {
  StereoPairer pairer(options());
  lock_with_offset_100(pairer);
  // The right camera's clock slipped most of a period: numbered partners are
  // now far apart in time, the next-numbered frame is the close one.
  for (int i = 3; i < 6; ++i) {
    pairer.add(frame(Side::kLeft, i * kPeriod, 1 + i));
    EXPECT_FALSE(pairer.add(frame(Side::kRight, i * kPeriod - 8 * kPeriod / 10, 101 + i)));
  }
  EXPECT_FALSE(pairer.locked());
  EXPECT_EQ(pairer.counts().unlocks, 1);
  pairer.add(frame(Side::kLeft, 6 * kPeriod, 7));
  auto pair = pairer.add(frame(Side::kRight, 7 * kPeriod - 8 * kPeriod / 10, 108));
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->left.frame_id, 7u);
  EXPECT_EQ(pair->right.frame_id, 108u);
}

TEST(FrameIdTracker, UnwrapsIntoASequence) {
  FrameIdTracker ids;
  EXPECT_EQ(ids.observe(65534).sequence, 0);
  EXPECT_EQ(ids.observe(65535).sequence, 1);
  EXPECT_EQ(ids.observe(1).sequence, 2);
  EXPECT_EQ(ids.observe(4).sequence, 5);
  EXPECT_EQ(ids.observe(3).sequence, 4);  // a late frame keeps its place
}

}  // namespace
}  // namespace ivoa::aravis_stereo
