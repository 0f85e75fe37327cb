#pragma once
// What the synthetic OpenNI2 depth sensor (libIvoaSynthDepth) shows: a flat
// wall at 2000 mm with a box at 1000 mm that moves 1 pixel to the right per
// frame, 640x480, plus an RGB view of the same. Plain C++ (no OpenCV) so the
// driver plugin stays small; tests use the same functions to check what the
// Kinect driver published.
//
// With depth-to-colour registration on, the depth image is re-projected
// into the colour camera, which is modelled as a fixed shift of
// kRegistrationShiftPx to the right, leaving the first columns invalid (0),
// as a real registration leaves its borders.
#include <cstdint>

namespace ivoa::sim_hardware::synth_depth {

inline constexpr int kWidth = 640;
inline constexpr int kHeight = 480;
inline constexpr int kFps = 30;
inline constexpr uint16_t kWallMm = 2000;
inline constexpr uint16_t kBoxMm = 1000;
inline constexpr int kBoxWidth = 120;
inline constexpr int kBoxHeight = 100;
inline constexpr int kBoxTop = 190;
inline constexpr int kBoxStartX = 60;   // box x at frame index 0
inline constexpr int kBoxTravel = 400;  // the box x repeats every kBoxTravel frames
inline constexpr int kRegistrationShiftPx = 12;

// Kinect v1 fields of view (libfreenect's OpenNI2 driver), radians.
inline constexpr float kDepthHfovRad = 1.0210f;  // 58.5 deg
inline constexpr float kDepthVfovRad = 0.7959f;  // 45.6 deg
inline constexpr float kColorHfovRad = 1.0821f;  // 62.0 deg
inline constexpr float kColorVfovRad = 0.8482f;  // 48.6 deg

struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

// Where the box is in frame `frame_index` (left edge moves +1 px per frame).
PixelRect box_at(int64_t frame_index, bool registered);

// Fills a kWidth x kHeight depth image (millimetres, 0 = invalid);
// `stride_px` is the row pitch in pixels.
void render_depth(int64_t frame_index, bool registered, uint16_t* depth_mm, int stride_px);

// Fills a kWidth x kHeight RGB888 image; `stride_bytes` is the row pitch.
void render_rgb(int64_t frame_index, uint8_t* rgb, int stride_bytes);

}  // namespace ivoa::sim_hardware::synth_depth
