#pragma once
// A latest-values mailbox for slow consumers (stereo, CNN): the receive side
// adds, the worker takes, and a value pushed out by newer ones before it
// was taken counts as dropped. With the default capacity of one the worker
// always gets the newest value (live: never work on a stale frame); a
// larger capacity holds that many of the newest, taken oldest first, so a
// short stall (start-up, a busy core) loses nothing while a sustained
// overload still cannot pile up more than `capacity` frames. LCM's own
// queue capacity is no substitute: when full it drops the *new* message,
// so a slow consumer would work on ever older frames.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace ivoa {

template <class T>
class LatestMailbox {
 public:
  explicit LatestMailbox(size_t capacity = 1) : capacity_(capacity) {
    if (capacity_ == 0) throw std::invalid_argument("LatestMailbox: capacity must be at least 1");
  }

  void put(T value) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      slots_.push_back(std::move(value));
      if (slots_.size() > capacity_) {
        slots_.pop_front();
        ++dropped_;
      }
      ++put_count_;
    }
    ready_.notify_one();
  }

  // The oldest value held (the newest with capacity 1), waiting up to
  // `timeout`; empty on timeout or once closed and emptied.
  std::optional<T> take(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return !slots_.empty() || closed_; });
    if (slots_.empty()) return std::nullopt;
    std::optional<T> out(std::move(slots_.front()));
    slots_.pop_front();
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
  size_t capacity() const { return capacity_; }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  uint64_t put_count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return put_count_;
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> slots_;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t put_count_ = 0;
};

}  // namespace ivoa
