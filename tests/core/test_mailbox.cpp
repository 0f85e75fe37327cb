#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>

#include "ivoa/core/mailbox.hpp"

namespace ivoa {
namespace {

TEST(Mailbox, KeepsOnlyTheNewestAndCountsDrops) {
  LatestMailbox<int> box;
  box.put(1);
  box.put(2);
  box.put(3);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 3);
  EXPECT_EQ(box.dropped(), 2u);
  EXPECT_EQ(box.put_count(), 3u);
  EXPECT_FALSE(box.take(std::chrono::milliseconds(1)));
}

// Held frames survive a stall of the worker, oldest first; beyond the
// capacity the oldest go, so an overload cannot pile up stale frames.
TEST(Mailbox, WithRoomForMoreKeepsTheNewestInOrder) {
  LatestMailbox<int> box(3);
  for (int v = 1; v <= 5; ++v) box.put(v);
  EXPECT_EQ(box.dropped(), 2u);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 3);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 4);
  box.put(6);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 5);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 6);
  EXPECT_FALSE(box.take(std::chrono::milliseconds(1)));
  EXPECT_EQ(box.dropped(), 2u);
  EXPECT_THROW(LatestMailbox<int>(0), std::invalid_argument);
}

TEST(Mailbox, ClosedStillHandsOutWhatItHolds) {
  LatestMailbox<int> box(2);
  box.put(1);
  box.put(2);
  box.close();
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 1);
  EXPECT_EQ(box.take(std::chrono::milliseconds(0)), 2);
  EXPECT_FALSE(box.take(std::chrono::milliseconds(0)));
}

TEST(Mailbox, WakesAWaitingConsumer) {
  LatestMailbox<int> box;
  std::thread producer([&] { box.put(7); });
  const auto got = box.take(std::chrono::seconds(10));
  producer.join();
  EXPECT_EQ(got, 7);
}

TEST(Mailbox, CloseReleasesWaiters) {
  LatestMailbox<int> box;
  std::thread closer([&] { box.close(); });
  EXPECT_FALSE(box.take(std::chrono::seconds(10)));
  closer.join();
  EXPECT_TRUE(box.closed());
}

}  // namespace
}  // namespace ivoa
