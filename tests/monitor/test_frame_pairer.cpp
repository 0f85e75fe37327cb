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

}  // namespace
}  // namespace ivoa::monitor
