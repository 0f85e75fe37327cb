// The paper's headline metric, as training validation and the live scorer count it.
#include <cmath>

#include <gtest/gtest.h>

#include "ivoa/core/label_confusion.hpp"

namespace ivoa {
namespace {

constexpr int kTP = 0, kTN = 1, kFP = 2, kFN = 3, kNone = -1;

TEST(LabelConfusion, MeanPerClassIsOverTheLabelsPresent) {
  LabelConfusion c;
  for (int i = 0; i < 3; ++i) c.add(kTN, kTN);
  c.add(kTN, kFP);
  c.add(kFN, kFN);
  c.add(kFN, kTN);
  c.add(kNone, kTN);  // no label: not counted
  c.add(kTP, 4);      // no such prediction: not counted
  EXPECT_EQ(c.total(), 6);
  EXPECT_EQ(c.count(kTN), 4);
  EXPECT_EQ(c.counts[kTN][kFP], 1);
  EXPECT_DOUBLE_EQ(c.recall(kTN), 0.75);
  EXPECT_DOUBLE_EQ(c.recall(kFN), 0.5);
  EXPECT_TRUE(std::isnan(c.recall(kTP)));
  EXPECT_DOUBLE_EQ(c.mean_per_class(), 0.625);
  EXPECT_DOUBLE_EQ(c.overall(), 4.0 / 6.0);
}

TEST(LabelConfusion, EmptyHasNoAccuracy) {
  const LabelConfusion empty;
  EXPECT_EQ(empty.total(), 0);
  EXPECT_TRUE(std::isnan(empty.mean_per_class()));
  EXPECT_TRUE(std::isnan(empty.overall()));
}

}  // namespace
}  // namespace ivoa
