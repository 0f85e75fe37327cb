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

}  // namespace
}  // namespace ivoa
