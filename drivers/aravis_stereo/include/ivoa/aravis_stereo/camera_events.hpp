#pragma once
// What camera threads tell the driver's main thread, through one queue so
// that only the main thread pairs and publishes.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "ivoa/aravis_stereo/camera_frame.hpp"

namespace ivoa::aravis_stereo {

struct CameraEvent {
  enum class Type {
    kFrame,         // a complete frame
    kIncomplete,    // a frame with lost packets, dropped; detail says why
    kConnected,     // the camera is open and streaming; detail describes it
    kDisconnected,  // the camera was lost and is being reopened; detail says why
    kFatal,         // the camera cannot be configured as asked; detail says why
  };
  Type type = Type::kFrame;
  Side side = Side::kLeft;
  CameraFrame frame;
  std::string detail;
};

class EventQueue {
 public:
  // At most `max_frames` frames wait; beyond that the oldest is dropped
  // (the main thread fell behind) and counted.
  explicit EventQueue(size_t max_frames = 16) : max_frames_(max_frames) {}

  void push(CameraEvent event) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (event.type == CameraEvent::Type::kFrame && ++frames_ > max_frames_) drop_oldest_frame_locked();
      events_.push_back(std::move(event));
    }
    ready_.notify_one();
  }

  // Waits up to `timeout` for events and takes them all.
  std::vector<CameraEvent> take(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [this] { return !events_.empty(); });
    std::vector<CameraEvent> out(std::make_move_iterator(events_.begin()), std::make_move_iterator(events_.end()));
    events_.clear();
    frames_ = 0;
    return out;
  }

  int64_t overflow_drops() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return overflow_drops_;
  }

 private:
  void drop_oldest_frame_locked() {
    for (auto it = events_.begin(); it != events_.end(); ++it) {
      if (it->type != CameraEvent::Type::kFrame) continue;
      events_.erase(it);
      --frames_;
      ++overflow_drops_;
      return;
    }
  }

  const size_t max_frames_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<CameraEvent> events_;
  size_t frames_ = 0;
  int64_t overflow_drops_ = 0;
};

}  // namespace ivoa::aravis_stereo
