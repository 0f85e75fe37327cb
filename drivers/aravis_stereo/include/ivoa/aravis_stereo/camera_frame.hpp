#pragma once
// One complete image from one camera of the stereo pair, copied out of the
// camera library's buffer so it can cross threads.
#include <cstdint>
#include <string>
#include <vector>

namespace ivoa::aravis_stereo {

enum class Side { kLeft = 0, kRight = 1 };
inline const char* side_name(Side side) { return side == Side::kLeft ? "left" : "right"; }

struct CameraFrame {
  Side side = Side::kLeft;
  int64_t utime = 0;            // when the frame reached the host, us since the epoch
  int64_t device_time_us = 0;   // the camera's own timestamp, us (0 = none)
  int64_t pairing_time_us = 0;  // the time frames are paired by (see PairingClock), us
  uint64_t frame_id = 0;        // the camera's frame counter (GigE Vision: 16-bit block id, wraps 65535 -> 1)
  int width = 0;                // pixels
  int height = 0;               // pixels
  int32_t pixelformat = 0;      // ivoa image_t PIXEL_FORMAT_* of `data`
  std::vector<uint8_t> data;    // rows of width * bytes-per-pixel, no padding
};

}  // namespace ivoa::aravis_stereo
