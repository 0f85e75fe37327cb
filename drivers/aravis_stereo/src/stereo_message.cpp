#include "ivoa/aravis_stereo/stereo_message.hpp"

#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::aravis_stereo {
namespace {

int bytes_per_pixel(int32_t pixelformat) {
  return pixelformat == image_t::PIXEL_FORMAT_RGB || pixelformat == image_t::PIXEL_FORMAT_BGR ? 3 : 1;
}

image_t raw_image(const CameraFrame& frame) {
  image_t msg;
  msg.utime = frame.utime;
  msg.width = frame.width;
  msg.height = frame.height;
  msg.row_stride = frame.width * bytes_per_pixel(frame.pixelformat);
  msg.pixelformat = frame.pixelformat;
  const size_t expected = static_cast<size_t>(msg.row_stride) * static_cast<size_t>(frame.height);
  if (frame.width <= 0 || frame.height <= 0 || frame.data.size() != expected)
    throw ImageError(std::string(side_name(frame.side)) + " frame " + std::to_string(frame.frame_id) + ": " +
                     std::to_string(frame.width) + "x" + std::to_string(frame.height) + " " +
                     pixelformat_name(frame.pixelformat) + " needs " + std::to_string(expected) + " bytes, has " +
                     std::to_string(frame.data.size()));
  msg.data = frame.data;
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

}  // namespace

std::optional<OutputFormat> parse_output_format(const std::string& name) {
  if (name == "raw") return OutputFormat::kRaw;
  if (name == "bgr") return OutputFormat::kBgr;
  if (name == "gray") return OutputFormat::kGray;
  return std::nullopt;
}

image_t frame_to_image(const CameraFrame& frame, OutputFormat format) {
  image_t raw = raw_image(frame);
  if (format == OutputFormat::kRaw) return raw;
  // The core conversions own the Bayer mapping (see bayer_to_bgr_code).
  const bool gray = format == OutputFormat::kGray;
  const cv::Mat pixels = decode_image(raw, gray ? ColorOutput::kGray : ColorOutput::kBgr);
  const int32_t wire = gray ? int32_t{image_t::PIXEL_FORMAT_GRAY} : int32_t{image_t::PIXEL_FORMAT_BGR};
  return encode_image(pixels, wire, frame.utime);
}

stereo_image_t make_stereo_message(const StereoPair& pair, OutputFormat format, int64_t seq,
                                   const std::string& source) {
  stereo_image_t msg;
  msg.utime = pair.left.utime;
  msg.seq = seq;
  msg.source = source;
  msg.left = frame_to_image(pair.left, format);
  msg.right = frame_to_image(pair.right, format);
  return msg;
}

}  // namespace ivoa::aravis_stereo
