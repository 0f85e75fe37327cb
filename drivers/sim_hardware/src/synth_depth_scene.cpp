#include "ivoa/sim_hardware/synth_depth_scene.hpp"

namespace ivoa::sim_hardware::synth_depth {

PixelRect box_at(int64_t frame_index, bool registered) {
  const int64_t phase = ((frame_index % kBoxTravel) + kBoxTravel) % kBoxTravel;
  PixelRect box;
  box.x = kBoxStartX + static_cast<int>(phase) + (registered ? kRegistrationShiftPx : 0);
  box.y = kBoxTop;
  box.width = kBoxWidth;
  box.height = kBoxHeight;
  return box;
}

void render_depth(int64_t frame_index, bool registered, uint16_t* depth_mm, int stride_px) {
  const PixelRect box = box_at(frame_index, registered);
  const int invalid_columns = registered ? kRegistrationShiftPx : 0;
  for (int y = 0; y < kHeight; ++y) {
    uint16_t* row = depth_mm + static_cast<int64_t>(y) * stride_px;
    const bool box_row = y >= box.y && y < box.y + box.height;
    for (int x = 0; x < kWidth; ++x) {
      uint16_t value = kWallMm;
      if (x < invalid_columns) value = 0;
      else if (box_row && x >= box.x && x < box.x + box.width) value = kBoxMm;
      row[x] = value;
    }
  }
}

void render_rgb(int64_t frame_index, uint8_t* rgb, int stride_bytes) {
  const PixelRect box = box_at(frame_index, true);
  for (int y = 0; y < kHeight; ++y) {
    uint8_t* row = rgb + static_cast<int64_t>(y) * stride_bytes;
    const bool box_row = y >= box.y && y < box.y + box.height;
    for (int x = 0; x < kWidth; ++x) {
      uint8_t* p = row + 3 * x;
      if (box_row && x >= box.x && x < box.x + box.width) {
        p[0] = 200, p[1] = 40, p[2] = 40;  // a red box
      } else {
        p[0] = static_cast<uint8_t>(x * 255 / kWidth), p[1] = static_cast<uint8_t>(y * 255 / kHeight), p[2] = 128;
      }
    }
  }
}

}  // namespace ivoa::sim_hardware::synth_depth
