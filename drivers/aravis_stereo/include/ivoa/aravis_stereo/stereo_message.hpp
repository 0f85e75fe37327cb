#pragma once
// Turns a pair of camera frames into the stereo_image_t the driver
// publishes, in the wire format the user picked.
#include <cstdint>
#include <optional>
#include <string>

#include "ivoa/aravis_stereo/stereo_pairer.hpp"

namespace ivoa {
class image_t;
class stereo_image_t;
}  // namespace ivoa

namespace ivoa::aravis_stereo {

enum class OutputFormat {
  kRaw,   // the camera's own pixel format (raw Bayer is a third the size of BGR)
  kBgr,   // demosaiced on the host (GenICam BayerRG8 -> cv::COLOR_BayerBG2BGR)
  kGray,  // 8-bit luminance
};

// "raw", "bgr", "gray"; nothing for anything else.
std::optional<OutputFormat> parse_output_format(const std::string& name);

// A frame's pixels as an image_t in `format`. Throws ivoa::ImageError if
// the frame's size does not match its data.
image_t frame_to_image(const CameraFrame& frame, OutputFormat format);

// utime is the left frame's host time.
stereo_image_t make_stereo_message(const StereoPair& pair, OutputFormat format, int64_t seq, const std::string& source);

}  // namespace ivoa::aravis_stereo
