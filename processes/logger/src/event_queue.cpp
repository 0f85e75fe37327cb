#include "ivoa/logger/event_queue.hpp"

#include <algorithm>

namespace ivoa::logger {

bool EventQueue::push(RecordedEvent&& event) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const uint64_t size = event.bytes();
    if (closed_ || (bytes_ > 0 && bytes_ + size > max_bytes_)) return false;
    bytes_ += size;
    peak_bytes_ = std::max(peak_bytes_, bytes_);
    events_.push_back(std::move(event));
  }
  not_empty_.notify_one();
  return true;
}

bool EventQueue::pop(RecordedEvent& event) {
  std::unique_lock<std::mutex> lock(mutex_);
  not_empty_.wait(lock, [this] { return !events_.empty() || closed_; });
  if (events_.empty()) return false;
  event = std::move(events_.front());
  events_.pop_front();
  bytes_ -= event.bytes();
  return true;
}

void EventQueue::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  not_empty_.notify_all();
}

size_t EventQueue::depth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return events_.size();
}

uint64_t EventQueue::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

uint64_t EventQueue::peak_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return peak_bytes_;
}

}  // namespace ivoa::logger
