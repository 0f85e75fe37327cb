#include "ivoa/openni2_kinect/recording_disk_watch.hpp"

#include <utility>

#include "ivoa/core/disk_space.hpp"

namespace ivoa::openni2_kinect {

RecordingDiskWatch::RecordingDiskWatch(std::string recording, DiskWatchLimits limits, FreeBytes free_bytes)
    : recording_(std::move(recording)),
      limits_(limits),
      free_bytes_(free_bytes ? std::move(free_bytes) : [path = recording_] { return free_bytes_for(path); }) {}

RecordingDiskWatch::Event RecordingDiskWatch::check(double now_s) {
  if (full_ || (last_look_s_ && now_s - *last_look_s_ < limits_.period_s)) return Event::kNone;
  last_look_s_ = now_s;
  const std::optional<uint64_t> free = free_bytes_();
  if (!free) return Event::kNone;  // a file system that cannot say: nothing to tell
  last_free_ = *free;
  if (*free < limits_.full_bytes) {
    full_ = true;
    return Event::kFull;
  }
  if (*free < limits_.low_bytes && !low_) {
    low_ = true;
    return Event::kLow;
  }
  return Event::kNone;
}

}  // namespace ivoa::openni2_kinect
