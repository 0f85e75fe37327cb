#pragma once
// The hand-over between the receive thread (which only copies payloads in)
// and the writer thread (which takes them out to disk). Bounded by bytes,
// not by count: one stereo pair is 3.5 MB, one heartbeat a few hundred
// bytes. When the disk cannot keep up and the bound is reached, the
// *incoming* message is refused, so everything already queued is kept and
// small messages still fit where a full image does not; the caller counts
// what was refused.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

namespace ivoa::logger {

struct RecordedEvent {
  std::string channel;
  int64_t timestamp = 0;  // receive time, microseconds since the epoch
  std::vector<uint8_t> data;

  uint64_t bytes() const { return channel.size() + data.size(); }
};

class EventQueue {
 public:
  explicit EventQueue(uint64_t max_bytes) : max_bytes_(max_bytes) {}

  // Takes the event unless it would take the queue past max_bytes (an
  // empty queue takes any one event) or the queue is closed.
  bool push(RecordedEvent&& event);
  // Waits for the next event; false once the queue is closed and empty.
  bool pop(RecordedEvent& event);
  // No more pushes; pop() still hands out what is queued.
  void close();

  size_t depth() const;
  uint64_t bytes() const;
  uint64_t peak_bytes() const;
  uint64_t max_bytes() const { return max_bytes_; }

 private:
  const uint64_t max_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_;
  std::deque<RecordedEvent> events_;
  uint64_t bytes_ = 0;
  uint64_t peak_bytes_ = 0;
  bool closed_ = false;
};

}  // namespace ivoa::logger
