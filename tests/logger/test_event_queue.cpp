// The hand-over queue: bounded by bytes, refusing the incoming message
// when full (never evicting what it holds), draining after close.
#include <gtest/gtest.h>

#include "ivoa/logger/event_queue.hpp"

namespace ivoa::logger {
namespace {

RecordedEvent event_of(size_t data_bytes, int64_t timestamp = 0) {
  RecordedEvent e;
  e.channel = "C";  // 1 byte
  e.timestamp = timestamp;
  e.data.assign(data_bytes, 0xAB);
  return e;
}

TEST(EventQueue, RefusesTheIncomingMessageWhenFullAndKeepsTheQueuedOnes) {
  EventQueue queue(10);
  EXPECT_TRUE(queue.push(event_of(4, 1)));  // 5 bytes
  EXPECT_TRUE(queue.push(event_of(4, 2)));  // 10 bytes: full
  EXPECT_FALSE(queue.push(event_of(4, 3)));
  EXPECT_EQ(queue.depth(), 2u);
  EXPECT_EQ(queue.bytes(), 10u);
  RecordedEvent out;
  ASSERT_TRUE(queue.pop(out));
  EXPECT_EQ(out.timestamp, 1);
  EXPECT_TRUE(queue.push(event_of(4, 4)));
  EXPECT_EQ(queue.peak_bytes(), 10u);
}

TEST(EventQueue, AnEmptyQueueTakesOneOversizedMessage) {
  EventQueue queue(10);
  EXPECT_TRUE(queue.push(event_of(100)));
  EXPECT_FALSE(queue.push(event_of(1)));
}

TEST(EventQueue, AfterCloseItRefusesPushesAndHandsOutWhatItHolds) {
  EventQueue queue(1000);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(queue.push(event_of(10, i)));
  queue.close();
  EXPECT_FALSE(queue.push(event_of(10)));
  RecordedEvent out;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(queue.pop(out));
    EXPECT_EQ(out.timestamp, i);
  }
  EXPECT_FALSE(queue.pop(out));
  EXPECT_EQ(queue.bytes(), 0u);
}

}  // namespace
}  // namespace ivoa::logger
