#pragma once
// Which clock left and right frames are paired by, and the mapping of a
// camera's own clock onto the host's.
//
// A frame reaches the host some transport delay after the camera stamped
// it: host receive time = device time + offset + delay, with delay >= 0 and
// smallest when nothing held the frame up. The smallest (host - device)
// over recent frames therefore estimates the clock offset, and device time
// + offset is a host-clock capture time free of the receive jitter (a busy
// CPU, a congested link) that makes receive times of one instant differ by
// tens of milliseconds.
#include <cstddef>
#include <cstdint>
#include <deque>

namespace ivoa::aravis_stereo {

enum class PairingClock {
  kMapped,  // each camera's clock mapped onto the host clock (default)
  kHost,    // when the frame's first packet reached the host
  kDevice,  // the cameras' own clocks as they are: only for PTP-synchronised cameras
};

class ClockMapper {
 public:
  explicit ClockMapper(size_t window = 64) : window_(window == 0 ? 1 : window) {}

  // Host-clock time (us) of a frame the camera stamped `device_us` and the
  // host received at `host_us`; `host_us` itself if the camera gives no
  // time (device_us == 0).
  int64_t map(int64_t device_us, int64_t host_us) {
    if (device_us == 0) return host_us;
    offsets_.push_back(host_us - device_us);
    if (offsets_.size() > window_) offsets_.pop_front();
    int64_t offset = offsets_.front();
    for (int64_t o : offsets_) offset = o < offset ? o : offset;
    return device_us + offset;
  }
  // After a reconnect: the camera's clock may have restarted.
  void reset() { offsets_.clear(); }

 private:
  size_t window_;
  std::deque<int64_t> offsets_;
};

}  // namespace ivoa::aravis_stereo
