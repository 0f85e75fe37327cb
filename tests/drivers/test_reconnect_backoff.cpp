#include <gtest/gtest.h>

#include "ivoa/aravis_stereo/reconnect_backoff.hpp"

namespace ivoa::aravis_stereo {
namespace {

TEST(ReconnectBackoff, DoublesUpToTheCeilingAndResetsAfterSuccess) {
  ReconnectBackoff backoff({0.5, 2.0, 3.0});
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 0.5);
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 1.0);
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 2.0);
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 3.0);
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 3.0);
  EXPECT_EQ(backoff.failures(), 5);
  backoff.succeeded();
  EXPECT_EQ(backoff.failures(), 0);
  EXPECT_DOUBLE_EQ(backoff.next_delay_s(), 0.5);
}

}  // namespace
}  // namespace ivoa::aravis_stereo
