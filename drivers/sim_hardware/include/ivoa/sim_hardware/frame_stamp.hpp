#pragma once
// A frame tick written into the image itself, so that a test at the far
// end of the real transport (GigE Vision, the driver, LCM) can tell which
// instant an image shows and check that a left/right pair shows the same
// one. 32 black/white blocks of 8x8 pixels in the top-left corner: 24 bits
// of tick, then an 8-bit check. Uniform 8x8 blocks survive Bayer mosaicing
// and demosaicing, so the stamp reads back from raw or debayered images.
#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

namespace ivoa::sim_hardware {

inline constexpr int kStampBlockPx = 8;
inline constexpr int kStampBits = 32;
inline constexpr int kStampWidthPx = kStampBlockPx * kStampBits;  // 256
inline constexpr uint32_t kStampTickMask = 0xFFFFFF;              // ticks are stamped modulo 2^24

// Writes `tick` (modulo 2^24) into an 8-bit gray or BGR image at least
// 256x8 pixels; a smaller image is left as it is.
void write_stamp(cv::Mat& image, uint32_t tick);

// The stamped tick, or nothing if the image carries no valid stamp.
std::optional<uint32_t> read_stamp(const cv::Mat& image);

}  // namespace ivoa::sim_hardware
