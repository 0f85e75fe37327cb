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
