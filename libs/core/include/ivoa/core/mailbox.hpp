#pragma once
// A latest-value mailbox for slow consumers (stereo, CNN): the receive side
// overwrites, the worker takes the newest value, and every value replaced
// before it was taken counts as dropped. LCM's own queue capacity is no
// substitute: when full it drops the *new* message, so a slow consumer
// would work on ever older frames.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>

namespace ivoa {

template <class T>
class LatestMailbox {
 public:
  void put(T value) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (slot_) ++dropped_;
      slot_ = std::move(value);
      ++put_count_;
    }
    ready_.notify_one();
  }

  // The newest value, waiting up to `timeout`; empty on timeout or once closed.
  std::optional<T> take(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return slot_.has_value() || closed_; });
    std::optional<T> out;
    out.swap(slot_);
    return out;
  }

  // Wakes waiting consumers; further takes return what is left, then empty.
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  bool closed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_;
  }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  uint64_t put_count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return put_count_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::optional<T> slot_;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t put_count_ = 0;
};

}  // namespace ivoa
