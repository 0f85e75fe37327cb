#pragma once
// The instant an image shows, written into the image itself, so that a test
// at the far end of the real transport (GigE Vision, the driver, LCM) can
// tell which instant it got and check that a left/right pair shows the same
// one. 32 black/white blocks of 8x8 pixels in the top-left corner: 23 bits
// of tick, an "off beat" bit, an 8-bit check. Uniform 8x8 blocks survive
// Bayer mosaicing and demosaicing, so the stamp reads back from raw or
// debayered images.
#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

namespace ivoa::sim_hardware {

inline constexpr int kStampBlockPx = 8;
inline constexpr int kStampBits = 32;
inline constexpr int kStampWidthPx = kStampBlockPx * kStampBits;  // 256
inline constexpr uint32_t kStampTickMask = 0x7FFFFF;              // ticks are stamped modulo 2^23

struct FrameStamp {
  uint32_t tick = 0;      // frame time in frame periods (or a trigger count), modulo 2^23
  bool off_beat = false;  // taken far from its tick's time (a starved simulator): the instant is ambiguous
  bool operator==(const FrameStamp& o) const { return tick == o.tick && off_beat == o.off_beat; }
};

// Writes the stamp into an 8-bit gray or BGR image at least 256x8 pixels;
// a smaller image is left as it is.
void write_stamp(cv::Mat& image, const FrameStamp& stamp);

// The stamp, or nothing if the image carries no valid one.
std::optional<FrameStamp> read_stamp(const cv::Mat& image);

}  // namespace ivoa::sim_hardware
