#include "ivoa/sim_hardware/frame_stamp.hpp"

namespace ivoa::sim_hardware {
namespace {

uint32_t check_byte(uint32_t payload) { return ((payload >> 16) ^ (payload >> 8) ^ payload ^ 0xA5u) & 0xFFu; }

// tick (23 bits), off-beat flag (1 bit), check (8 bits).
uint32_t stamp_word(const FrameStamp& stamp) {
  const uint32_t payload = ((stamp.tick & kStampTickMask) << 1) | (stamp.off_beat ? 1u : 0u);
  return (payload << 8) | check_byte(payload);
}

bool fits(const cv::Mat& image) {
  return image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3) && image.cols >= kStampWidthPx &&
         image.rows >= kStampBlockPx;
}

}  // namespace

void write_stamp(cv::Mat& image, const FrameStamp& stamp) {
  if (!fits(image)) return;
  const uint32_t word = stamp_word(stamp);
  for (int bit = 0; bit < kStampBits; ++bit) {
    const bool one = (word >> (kStampBits - 1 - bit)) & 1u;
    const cv::Rect block(bit * kStampBlockPx, 0, kStampBlockPx, kStampBlockPx);
    image(block).setTo(cv::Scalar::all(one ? 255 : 0));
  }
}

std::optional<FrameStamp> read_stamp(const cv::Mat& image) {
  if (!fits(image)) return std::nullopt;
  uint32_t word = 0;
  const int centre = kStampBlockPx / 2;
  for (int bit = 0; bit < kStampBits; ++bit) {
    const int x = bit * kStampBlockPx + centre;
    // Gray, or the mean of B, G, R: a stamp block is the same in every channel.
    int value = 0;
    if (image.channels() == 1) {
      value = image.at<uint8_t>(centre, x);
    } else {
      const auto& p = image.at<cv::Vec3b>(centre, x);
      value = (p[0] + p[1] + p[2]) / 3;
    }
    if (value > 64 && value < 192) return std::nullopt;  // not a black/white block
    word = (word << 1) | (value >= 192 ? 1u : 0u);
  }
  const uint32_t payload = word >> 8;
  if ((word & 0xFFu) != check_byte(payload)) return std::nullopt;
  return FrameStamp{payload >> 1, (payload & 1u) != 0};
}

}  // namespace ivoa::sim_hardware
