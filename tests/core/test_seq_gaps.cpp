#include <cstdint>

#include <gtest/gtest.h>

#include "ivoa/core/seq_gaps.hpp"

namespace ivoa {
namespace {

TEST(SeqGaps, CountsTheNumbersSkippedAndStartsAgainWhenSeqGoesBack) {
  SeqGaps gaps;
  EXPECT_EQ(gaps.add(7), 0) << "the first frame seen: nothing known before it";
  EXPECT_EQ(gaps.add(8), 0);
  EXPECT_EQ(gaps.add(12), 3);
  EXPECT_EQ(gaps.add(12), 0) << "a repeat is not a gap";
  EXPECT_EQ(gaps.add(0), 0) << "the publisher restarted";
  EXPECT_EQ(gaps.add(2), 1);
}

TEST(SeqGaps, AFarJumpCountsOnceTheNextFrameFollowsIt) {
  SeqGaps gaps;
  gaps.add(100);
  EXPECT_EQ(gaps.add(5100), 0) << "held: is it the publisher's numbering or one damaged seq?";
  EXPECT_EQ(gaps.add(5102), 4999 + 1) << "the numbering jumped: 101..5099, and 5101";
  EXPECT_EQ(gaps.add(5103), 0);
}

// Far either way or a little back: a seq -7 between 100 and 101 once
// counted 107 frames missed when 101 came.
TEST(SeqGaps, OneWrongSeqIsForgotten) {
  SeqGaps gaps;
  gaps.add(100);
  int64_t next = 101;
  for (const int64_t wrong : {INT64_MAX, INT64_MIN, int64_t{-5000}, int64_t{1'000'000}, int64_t{-7}, int64_t{97}}) {
    EXPECT_EQ(gaps.add(wrong), 0) << wrong;
    EXPECT_EQ(gaps.add(next), 0) << "after " << wrong << ": the next frame continues from " << next - 1;
    ++next;
  }
  EXPECT_EQ(gaps.add(INT64_MAX), 0);
  EXPECT_EQ(gaps.add(next + 2), 2) << "a gap right after the wrong seq still counts";
}

TEST(SeqGaps, AFarStepBackThatContinuesIsARestart) {
  SeqGaps gaps;
  gaps.add(90'000);
  EXPECT_EQ(gaps.add(0), 0);
  EXPECT_EQ(gaps.add(1), 0) << "the publisher restarted from 0: nothing missed";
  EXPECT_EQ(gaps.add(4), 2);
}

TEST(SeqGaps, ExtremeSeqsDoNotOverflow) {
  SeqGaps gaps;
  gaps.add(INT64_MAX - 1);
  EXPECT_EQ(gaps.add(INT64_MAX), 0);
  gaps.add(INT64_MIN);
  EXPECT_EQ(gaps.add(INT64_MIN + 3), 2) << "held, followed: a restart from the lowest seq, 2 missed after it";
}

}  // namespace
}  // namespace ivoa
