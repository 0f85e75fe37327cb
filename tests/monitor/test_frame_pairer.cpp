#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "ivoa/monitor/frame_pairer.hpp"

namespace ivoa::monitor {
namespace {

using Pairer = FramePairer<std::string, std::string>;
using Results = std::vector<Pairer::Result>;

void append(Results& all, Results more) {
  for (auto& r : more) all.push_back(std::move(r));
}

TEST(FramePairer, PairsWithTheNearestDepthFrame) {
  Pairer p;
  Results out;
  append(out, p.add_depth(1000, "d1000"));
  append(out, p.add_depth(34000, "d34000"));
  append(out, p.add_stereo(30000, "s30000"));  // 4 ms from d34000, 29 ms from d1000
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stereo, "s30000");
  ASSERT_TRUE(out[0].depth_utime);
  EXPECT_EQ(*out[0].depth, "d34000");
}

TEST(FramePairer, StereoBeforeItsDepthWaitsInsteadOfPairingWrongly) {
  Pairer p;
  Results out;
  append(out, p.add_depth(0, "d0"));
  append(out, p.add_stereo(30000, "s30000"));  // d0 is 30 ms away; the right one is yet to come
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(p.pending(), 1u);
  append(out, p.add_depth(33000, "d33000"));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(*out[0].depth, "d33000");
}

TEST(FramePairer, MissingPartnerIsUnmatchedNotPairedWithAFarFrame) {
  Pairer p;
  Results out;
  append(out, p.add_depth(0, "d0"));
  append(out, p.add_depth(100000, "d100000"));  // depth dropped frames in between
  append(out, p.add_stereo(50000, "s50000"));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_FALSE(out[0].depth_utime);
  EXPECT_EQ(out[0].depth, nullptr);
  EXPECT_EQ(p.counters().unmatched_stereo, 1);
  EXPECT_EQ(p.counters().paired, 0);
  EXPECT_EQ(out[0].nearest_depth_us, 50000) << "says how far the nearest depth frame was";
  append(out, p.add_stereo(130000, "s130000"));
  append(out, p.add_depth(200000, "d200000"));
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].nearest_depth_us, -30000) << "an older one, by its sign";
}

TEST(FramePairer, DepthStreamStallDecidesPendingFramesEventually) {
  Pairer p;
  Results out;
  append(out, p.add_stereo(0, "s0"));
  EXPECT_TRUE(out.empty());
  append(out, p.add_stereo(600000, "s600000"));  // stereo time moved on by > max_wait
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stereo, "s0");
  EXPECT_FALSE(out[0].depth_utime);
  append(out, p.flush());
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(p.pending(), 0u);
}

TEST(FramePairer, DuplicateUtimesAreIgnoredAndCounted) {
  Pairer p;
  Results out;
  append(out, p.add_depth(1000, "first"));
  append(out, p.add_depth(1000, "second"));
  append(out, p.add_stereo(1000, "s"));
  append(out, p.add_stereo(1000, "s again"));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(*out[0].depth, "first");
  EXPECT_EQ(p.counters().duplicate_depth, 1);
  EXPECT_EQ(p.counters().duplicate_stereo, 1);
}

TEST(FramePairer, OutOfOrderStereoArrivalStillPairsEach) {
  Pairer p;
  Results out;
  for (int64_t t = 0; t <= 200000; t += 33333) append(out, p.add_depth(t + 3000, "d" + std::to_string(t + 3000)));
  append(out, p.add_stereo(66666, "s2"));
  append(out, p.add_stereo(33333, "s1"));  // arrives after a later frame
  ASSERT_EQ(out.size(), 2u);
  for (const auto& r : out) {
    ASSERT_TRUE(r.depth_utime);
    EXPECT_EQ(*r.depth_utime, r.stereo_utime + 3000);
  }
}

TEST(FramePairer, LateDepthFramesAreCounted) {
  Pairer p;
  Results out;
  append(out, p.add_depth(40000, "d40000"));
  append(out, p.add_stereo(40000, "s40000"));
  append(out, p.add_depth(5000, "late"));
  EXPECT_EQ(p.counters().late_depth, 1);
}

// A 30 Hz pair of streams, depth 2 ms after stereo, from utime `start` for `n` frames.
void feed(Pairer& p, Results& out, int64_t start, int n) {
  for (int i = 0; i < n; ++i) {
    const int64_t t = start + i * 33'333;
    append(out, p.add_depth(t + 2'000, "d" + std::to_string(t + 2'000)));
    append(out, p.add_stereo(t, "s" + std::to_string(t)));
  }
}

size_t paired(const Results& out) {
  size_t n = 0;
  for (const auto& r : out) n += r.depth_utime.has_value();
  return n;
}

TEST(FramePairer, OneDepthFrameFarInTheFutureIsIgnoredNotTheEndOfThePairing) {
  Pairer p;
  Results out;
  feed(p, out, 1'000'000, 10);
  append(out, p.add_depth(2'000'000'000'000'000, "wrong clock"));
  feed(p, out, 1'333'330, 10);
  append(out, p.flush());
  EXPECT_EQ(out.size(), 20u);
  EXPECT_EQ(paired(out), 20u);
  EXPECT_EQ(p.counters().depth_clock.outliers, 1);
  EXPECT_NE(p.last_clock_event().find("depth frame at utime 2000000000000000 is +1999999998.6 s from its stream's"),
            std::string::npos)
      << p.last_clock_event();
  // one far in the past is as harmless
  append(out, p.add_stereo(5, "wrong clock"));
  feed(p, out, 1'666'660, 3);
  append(out, p.flush());
  EXPECT_EQ(paired(out), 23u);
  EXPECT_EQ(p.counters().stereo_clock.outliers, 1);
  // as is the farthest (its distance overflowed: counted late, not an outlier)
  append(out, p.add_depth(INT64_MIN, "wrong clock"));
  feed(p, out, 2'000'000, 3);
  append(out, p.flush());
  EXPECT_EQ(paired(out), 26u);
  EXPECT_EQ(p.counters().depth_clock.outliers, 2);
  EXPECT_EQ(p.counters().late_depth, 0);
}

TEST(FramePairer, AGapInBothStreamsIsFollowed) {
  Pairer p;
  Results out;
  feed(p, out, 1'000'000, 5);
  feed(p, out, 9'000'000, 5);  // 8 s later, e.g. the recording paused
  append(out, p.flush());
  EXPECT_EQ(paired(out), 10u);
  EXPECT_EQ(p.counters().depth_clock.outliers + p.counters().stereo_clock.outliers, 0);
  EXPECT_EQ(p.counters().depth_clock.restarts + p.counters().stereo_clock.restarts, 0);
}

// Frames 1.5 s apart step more than a jump (1 s) every time: each was held,
// then ignored because the next did not come within a jump of it, so
// nothing was ever labelled. The stream's own step now sets how far ahead
// its next frame may come; a single wrong utime is still ignored.
TEST(FramePairer, AStreamSlowerThanOneFrameAJumpIsPaired) {
  Pairer p;
  Results out;
  const auto slow = [&](int from, int to) {
    for (int i = from; i < to; ++i) {
      const int64_t t = 1'000'000 + i * int64_t{1'500'000};
      append(out, p.add_depth(t + 2'000, "slow"));
      append(out, p.add_stereo(t, "slow"));
    }
  };
  slow(0, 8);
  append(out, p.flush());
  EXPECT_EQ(out.size(), 8u);
  EXPECT_EQ(paired(out), 8u);
  EXPECT_EQ(p.counters().depth_clock.outliers + p.counters().stereo_clock.outliers, 0);

  append(out, p.add_depth(900'000'000, "wrong clock"));  // 888 s ahead
  slow(8, 12);
  append(out, p.flush());
  EXPECT_EQ(paired(out), 12u);
  EXPECT_EQ(p.counters().depth_clock.outliers, 1);
}

// The step that lets a slow stream through must not let one wrong utime
// through with it: not when the stream speeds up (a frame 3.5 s ahead,
// taken, made the next frames a "restart" that paired nothing again), nor
// 2.9 s ahead of a stream of 1.5 s steps (it was taken, the good frame after
// it dropped).
TEST(FramePairer, AWrongUtimeIsStillIgnoredWhenTheStreamIsSlowOrSpeedsUp) {
  Pairer p;
  Results out;
  const auto both = [&](int64_t t) {
    append(out, p.add_depth(t + 2'000, "d"));
    append(out, p.add_stereo(t, "s"));
  };
  for (int i = 0; i < 5; ++i) both(1'000'000 + i * int64_t{2'000'000});  // 0.5 Hz
  for (int i = 1; i <= 3; ++i) both(9'000'000 + i * 33'333);             // then 30 Hz
  append(out, p.add_depth(12'600'000, "wrong clock"));
  for (int i = 4; i <= 6; ++i) both(9'000'000 + i * 33'333);
  append(out, p.flush());
  EXPECT_EQ(paired(out), 11u);
  EXPECT_EQ(p.counters().depth_clock.restarts, 0);
  EXPECT_EQ(p.counters().depth_clock.outliers, 1);

  Pairer slow;
  Results slow_out;
  for (int i = 0; i < 8; ++i) {
    const int64_t t = 1'000'000 + i * int64_t{1'500'000};
    append(slow_out, slow.add_depth(t + 2'000, "d"));
    append(slow_out, slow.add_stereo(t, "s"));
  }
  append(slow_out, slow.add_depth(14'400'000, "wrong clock"));  // 2.9 s after the newest, 11.5 s
  for (int i = 8; i < 10; ++i) {
    const int64_t t = 1'000'000 + i * int64_t{1'500'000};
    append(slow_out, slow.add_depth(t + 2'000, "d"));
    append(slow_out, slow.add_stereo(t, "s"));
  }
  append(slow_out, slow.flush());
  EXPECT_EQ(paired(slow_out), 10u);
  EXPECT_EQ(slow.counters().depth_clock.outliers, 1);

  // 30 Hz: a wrong utime 4.3 s ahead, then a real 9.3 s gap in the stream
  Pairer fast;
  Results fast_out;
  for (int i = 0; i < 6; ++i) append(fast_out, fast.add_depth(1'000'000 + i * 33'333, "d"));
  append(fast_out, fast.add_depth(5'466'665, "wrong clock"));
  for (int i = 0; i < 3; ++i) append(fast_out, fast.add_depth(10'466'665 + i * 33'333, "after the gap"));
  EXPECT_EQ(fast.counters().depth_clock.outliers, 1);
  EXPECT_EQ(fast.counters().depth_clock.restarts, 0);
}

TEST(FramePairer, ALogPlayedAgainIsPairedAgain) {
  Pairer p;
  Results out;
  feed(p, out, 1'000'000, 60);
  // The detector lags: the second play's depth frames start before the first play's last grids.
  for (int i = 0; i < 3; ++i) append(out, p.add_depth(1'002'000 + i * 33'333, "again"));
  for (int i = 57; i < 60; ++i) append(out, p.add_stereo(1'000'000 + i * 33'333 + 1, "late grid"));
  for (int i = 0; i < 60; ++i) {
    const int64_t t = 1'000'000 + i * 33'333;
    if (i >= 3) append(out, p.add_depth(t + 2'000, "again"));
    append(out, p.add_stereo(t, "again"));
  }
  append(out, p.flush());
  EXPECT_EQ(out.size(), 123u);
  EXPECT_EQ(paired(out), 123u);
  EXPECT_EQ(p.counters().depth_clock.restarts, 1);
  EXPECT_EQ(p.counters().stereo_clock.restarts, 1);
  EXPECT_EQ(p.counters().duplicate_stereo + p.counters().duplicate_depth + p.counters().late_depth, 0);
}

TEST(FramePairer, ADepthLogLoopingWhileStereoIsSilentKeepsBoundedMemory) {
  Pairer p;  // default: keeps 2 s of depth, the newest 2 restarts ahead of stereo's
  Results out;
  constexpr int kPlays = 10, kFrames = 36;  // a 1.2 s depth log at 30 Hz, looped
  for (int play = 0; play < kPlays; ++play)
    for (int i = 0; i < kFrames; ++i) append(out, p.add_depth(1'000'000 + i * 33'333, "depth"));
  EXPECT_EQ(p.counters().depth_clock.restarts, kPlays - 1);
  // The first play (the stereo stream's) and the last two, not all ten.
  EXPECT_EQ(p.buffered_depth(), 3u * kFrames);
  EXPECT_EQ(p.counters().dropped_depth, (kPlays - 3) * kFrames);
  // The detector comes up late: its first play still pairs with the depth log's first.
  for (int i = 0; i < kFrames; ++i) append(out, p.add_stereo(1'000'000 + i * 33'333 + 1, "grid"));
  append(out, p.flush());
  EXPECT_EQ(paired(out), static_cast<size_t>(kFrames));
}

}  // namespace
}  // namespace ivoa::monitor
