#include "ivoa/core/image_convert.hpp"

#include <algorithm>
#include <cstdlib>
#include <climits>
#include <cstring>
#include <optional>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw ImageError(what);
}

// Wraps the raw pixels of msg (no copy) after checking its size against
// the bytes; decode_image has checked width and height.
cv::Mat wrap_raw(const image_t& msg, int type, int bytes_per_pixel) {
  // int64: a width near INT_MAX times 3 must not wrap round to pass
  require(static_cast<int64_t>(msg.row_stride) >= static_cast<int64_t>(msg.width) * bytes_per_pixel,
          "row_stride " + std::to_string(msg.row_stride) + " is smaller than width * " +
              std::to_string(bytes_per_pixel) + " for " + pixelformat_name(msg.pixelformat));
  const size_t needed = static_cast<size_t>(msg.row_stride) * static_cast<size_t>(msg.height);
  require(msg.data.size() >= needed, pixelformat_name(msg.pixelformat) + " image " + std::to_string(msg.width) + "x" +
                                         std::to_string(msg.height) + " needs " + std::to_string(needed) +
                                         " bytes, message has " + std::to_string(msg.data.size()));
  return cv::Mat(msg.height, msg.width, type, const_cast<uint8_t*>(msg.data.data()),
                 static_cast<size_t>(msg.row_stride));
}

uint32_t big_endian(const uint8_t* p, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// Width and height from a PNG's IHDR chunk, which must come first.
std::optional<cv::Size> png_header_size(const std::vector<uint8_t>& d) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (d.size() < 24 || std::memcmp(d.data(), kSignature, 8) != 0 || std::memcmp(d.data() + 12, "IHDR", 4) != 0)
    return std::nullopt;
  return cv::Size(static_cast<int>(std::min<uint32_t>(big_endian(&d[16], 4), INT32_MAX)),
                  static_cast<int>(std::min<uint32_t>(big_endian(&d[20], 4), INT32_MAX)));
}

// Width and height from a JPEG's first start-of-frame segment, walking the
// segments before it by their lengths.
std::optional<cv::Size> jpeg_header_size(const std::vector<uint8_t>& d) {
  if (d.size() < 4 || d[0] != 0xFF || d[1] != 0xD8) return std::nullopt;
  size_t at = 2;
  while (at + 4 <= d.size()) {
    if (d[at] != 0xFF) return std::nullopt;
    const uint8_t marker = d[at + 1];
    if (marker == 0xFF) {  // fill byte before a marker
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length field
      at += 2;
      continue;
    }
    const size_t length = big_endian(&d[at + 2], 2);
    const bool start_of_frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (start_of_frame) {
      if (length < 7 || at + 9 > d.size()) return std::nullopt;
      return cv::Size(static_cast<int>(big_endian(&d[at + 7], 2)), static_cast<int>(big_endian(&d[at + 5], 2)));
    }
    if (marker == 0xDA || length < 2) return std::nullopt;  // scan data before any frame header
    at += 2 + length;
  }
  return std::nullopt;
}

// Refuses a compressed image whose header is missing or whose size is not
// the message's, before it is decompressed.
void check_compressed_header(const image_t& msg) {
  const bool png = msg.pixelformat == image_t::PIXEL_FORMAT_PNG;
  const std::string name = pixelformat_name(msg.pixelformat);
  const auto size = png ? png_header_size(msg.data) : jpeg_header_size(msg.data);
  require(size.has_value(), name + " data has no readable " + name + " header");
  require(size->width == msg.width && size->height == msg.height,
          name + " header says " + std::to_string(size->width) + "x" + std::to_string(size->height) +
              " but the message says " + std::to_string(msg.width) + "x" + std::to_string(msg.height));
}

cv::Mat to_output(const cv::Mat& src, ColorOutput output) {
  const bool want_color = output == ColorOutput::kBgr;
  if ((src.channels() == 3) == want_color) return src.clone();
  cv::Mat out;
  cv::cvtColor(src, out, want_color ? cv::COLOR_GRAY2BGR : cv::COLOR_BGR2GRAY);
  return out;
}

}  // namespace

bool is_bayer(int32_t f) {
  return f == image_t::PIXEL_FORMAT_BAYER_RGGB || f == image_t::PIXEL_FORMAT_BAYER_BGGR ||
         f == image_t::PIXEL_FORMAT_BAYER_GBRG || f == image_t::PIXEL_FORMAT_BAYER_GRBG;
}

std::string pixelformat_name(int32_t f) {
  switch (f) {
    case image_t::PIXEL_FORMAT_GRAY: return "GRAY";
    case image_t::PIXEL_FORMAT_RGB: return "RGB";
    case image_t::PIXEL_FORMAT_BGR: return "BGR";
    case image_t::PIXEL_FORMAT_BAYER_RGGB: return "BAYER_RGGB";
    case image_t::PIXEL_FORMAT_BAYER_BGGR: return "BAYER_BGGR";
    case image_t::PIXEL_FORMAT_BAYER_GBRG: return "BAYER_GBRG";
    case image_t::PIXEL_FORMAT_BAYER_GRBG: return "BAYER_GRBG";
    case image_t::PIXEL_FORMAT_JPEG: return "JPEG";
    case image_t::PIXEL_FORMAT_PNG: return "PNG";
    default: return "unknown pixel format " + std::to_string(f);
  }
}

int bayer_to_bgr_code(int32_t f) {
  // OpenCV names Bayer patterns by the second row's second and third pixels.
  switch (f) {
    case image_t::PIXEL_FORMAT_BAYER_RGGB: return cv::COLOR_BayerBG2BGR;
    case image_t::PIXEL_FORMAT_BAYER_BGGR: return cv::COLOR_BayerRG2BGR;
    case image_t::PIXEL_FORMAT_BAYER_GBRG: return cv::COLOR_BayerGR2BGR;
    case image_t::PIXEL_FORMAT_BAYER_GRBG: return cv::COLOR_BayerGB2BGR;
    default: throw ImageError("not a Bayer pixel format: " + pixelformat_name(f));
  }
}

cv::Mat mosaic_bayer(const cv::Mat& bgr, int32_t f) {
  require(bgr.type() == CV_8UC3, "mosaic_bayer needs an 8-bit BGR image");
  // Channel index (B=0, G=1, R=2) of the filter at (row parity, column parity).
  int pattern[2][2];
  switch (f) {
    case image_t::PIXEL_FORMAT_BAYER_RGGB:
      pattern[0][0] = 2;
      pattern[0][1] = 1;
      pattern[1][0] = 1;
      pattern[1][1] = 0;
      break;
    case image_t::PIXEL_FORMAT_BAYER_BGGR:
      pattern[0][0] = 0;
      pattern[0][1] = 1;
      pattern[1][0] = 1;
      pattern[1][1] = 2;
      break;
    case image_t::PIXEL_FORMAT_BAYER_GBRG:
      pattern[0][0] = 1;
      pattern[0][1] = 0;
      pattern[1][0] = 2;
      pattern[1][1] = 1;
      break;
    case image_t::PIXEL_FORMAT_BAYER_GRBG:
      pattern[0][0] = 1;
      pattern[0][1] = 2;
      pattern[1][0] = 0;
      pattern[1][1] = 1;
      break;
    default: throw ImageError("not a Bayer pixel format: " + pixelformat_name(f));
  }
  cv::Mat raw(bgr.size(), CV_8UC1);
  for (int r = 0; r < bgr.rows; ++r) {
    const auto* src = bgr.ptr<cv::Vec3b>(r);
    auto* dst = raw.ptr<uint8_t>(r);
    const int* row_pattern = pattern[r & 1];
    for (int c = 0; c < bgr.cols; ++c) dst[c] = src[c][row_pattern[c & 1]];
  }
  return raw;
}

std::string stereo_times_error(const stereo_image_t& msg) {
  const auto apart = [](int64_t a, int64_t b) { return a != 0 && b != 0 && std::llabs(a - b) > kMaxStereoSkewUs; };
  const auto ms = [](int64_t a, int64_t b) { return std::to_string(std::llabs(a - b) / 1000) + " ms"; };
  if (apart(msg.left.utime, msg.right.utime))
    return "its left and right images were taken " + ms(msg.left.utime, msg.right.utime) + " apart";
  if (apart(msg.utime, msg.left.utime) || apart(msg.utime, msg.right.utime))
    return "its images' utimes lie " +
           ms(msg.utime, apart(msg.utime, msg.left.utime) ? msg.left.utime : msg.right.utime) + " from the pair's";
  return "";
}

cv::Mat decode_image(const image_t& msg, ColorOutput output) {
  require(static_cast<size_t>(msg.size) == msg.data.size(), "image size field " + std::to_string(msg.size) +
                                                                " disagrees with " + std::to_string(msg.data.size()) +
                                                                " data bytes");
  require(msg.width > 0 && msg.height > 0 &&
              static_cast<int64_t>(msg.width) * static_cast<int64_t>(msg.height) <= kMaxImagePixels,
          "image size " + std::to_string(msg.width) + "x" + std::to_string(msg.height) + " is not between 1 and " +
              std::to_string(kMaxImagePixels) + " pixels");
  const int32_t f = msg.pixelformat;
  if (f == image_t::PIXEL_FORMAT_GRAY) return to_output(wrap_raw(msg, CV_8UC1, 1), output);
  if (f == image_t::PIXEL_FORMAT_BGR) return to_output(wrap_raw(msg, CV_8UC3, 3), output);
  if (f == image_t::PIXEL_FORMAT_RGB) {
    cv::Mat bgr;
    cv::cvtColor(wrap_raw(msg, CV_8UC3, 3), bgr, cv::COLOR_RGB2BGR);
    return output == ColorOutput::kBgr ? bgr : to_output(bgr, output);
  }
  if (is_bayer(f)) {
    cv::Mat bgr;
    cv::cvtColor(wrap_raw(msg, CV_8UC1, 1), bgr, bayer_to_bgr_code(f));
    return output == ColorOutput::kBgr ? bgr : to_output(bgr, output);
  }
  if (f == image_t::PIXEL_FORMAT_JPEG || f == image_t::PIXEL_FORMAT_PNG) {
    require(!msg.data.empty(), pixelformat_name(f) + " image has no data");
    check_compressed_header(msg);
    const cv::Mat buffer(1, static_cast<int>(msg.data.size()), CV_8UC1, const_cast<uint8_t*>(msg.data.data()));
    cv::Mat decoded = cv::imdecode(buffer, output == ColorOutput::kBgr ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
    require(!decoded.empty(), pixelformat_name(f) + " data does not decode");
    require(decoded.cols == msg.width && decoded.rows == msg.height,
            pixelformat_name(f) + " decodes to " + std::to_string(decoded.cols) + "x" + std::to_string(decoded.rows) +
                " but the message says " + std::to_string(msg.width) + "x" + std::to_string(msg.height));
    return decoded;
  }
  throw ImageError("cannot decode " + pixelformat_name(f));
}

image_t encode_image(const cv::Mat& image, int32_t f, int64_t utime, int jpeg_quality) {
  require(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3),
          "encode_image needs an 8-bit gray or BGR image");
  const bool color = image.channels() == 3;
  image_t msg;
  msg.utime = utime;
  msg.width = image.cols;
  msg.height = image.rows;
  msg.pixelformat = f;
  cv::Mat raw;
  if (f == image_t::PIXEL_FORMAT_GRAY) {
    raw = color ? to_output(image, ColorOutput::kGray) : image;
  } else if (f == image_t::PIXEL_FORMAT_BGR) {
    raw = color ? image : to_output(image, ColorOutput::kBgr);
  } else if (f == image_t::PIXEL_FORMAT_RGB) {
    cv::cvtColor(color ? image : to_output(image, ColorOutput::kBgr), raw, cv::COLOR_BGR2RGB);
  } else if (is_bayer(f)) {
    raw = mosaic_bayer(color ? image : to_output(image, ColorOutput::kBgr), f);
  } else if (f == image_t::PIXEL_FORMAT_JPEG || f == image_t::PIXEL_FORMAT_PNG) {
    std::vector<int> params;
    if (f == image_t::PIXEL_FORMAT_JPEG) params = {cv::IMWRITE_JPEG_QUALITY, jpeg_quality};
    else params = {cv::IMWRITE_PNG_COMPRESSION, 1};
    require(cv::imencode(f == image_t::PIXEL_FORMAT_JPEG ? ".jpg" : ".png", image, msg.data, params),
            "cannot encode " + pixelformat_name(f));
    msg.row_stride = 0;
    msg.size = static_cast<int32_t>(msg.data.size());
    return msg;
  } else {
    throw ImageError("cannot encode " + pixelformat_name(f));
  }
  const size_t row_bytes = raw.cols * raw.elemSize();
  msg.row_stride = static_cast<int32_t>(row_bytes);
  msg.data.resize(row_bytes * static_cast<size_t>(raw.rows));
  for (int r = 0; r < raw.rows; ++r) std::memcpy(msg.data.data() + row_bytes * r, raw.ptr(r), row_bytes);
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

cv::Mat decode_depth(const depth_image_t& msg) {
  require(msg.format == depth_image_t::FORMAT_MM_U16LE,
          "depth image format " + std::to_string(msg.format) + " is not FORMAT_MM_U16LE");
  require(msg.width > 0 && msg.height > 0,
          "depth image has non-positive size " + std::to_string(msg.width) + "x" + std::to_string(msg.height));
  const size_t needed = static_cast<size_t>(msg.width) * static_cast<size_t>(msg.height) * 2;
  require(static_cast<size_t>(msg.size) == msg.data.size() && msg.data.size() == needed,
          "depth image " + std::to_string(msg.width) + "x" + std::to_string(msg.height) + " needs " +
              std::to_string(needed) + " bytes, message has " + std::to_string(msg.data.size()));
  cv::Mat depth(msg.height, msg.width, CV_16UC1);
  const uint8_t* src = msg.data.data();
  for (int r = 0; r < msg.height; ++r) {
    auto* dst = depth.ptr<uint16_t>(r);
    for (int c = 0; c < msg.width; ++c, src += 2) dst[c] = static_cast<uint16_t>(src[0] | (src[1] << 8));
  }
  return depth;
}

depth_image_t encode_depth(const cv::Mat& depth_mm, double fx, double fy, double cx, double cy, int64_t utime) {
  require(depth_mm.type() == CV_16UC1, "encode_depth needs a CV_16UC1 image in millimetres");
  depth_image_t msg;
  msg.utime = utime;
  msg.width = depth_mm.cols;
  msg.height = depth_mm.rows;
  msg.fx = fx;
  msg.fy = fy;
  msg.cx = cx;
  msg.cy = cy;
  msg.format = depth_image_t::FORMAT_MM_U16LE;
  msg.data.resize(depth_mm.total() * 2);
  uint8_t* dst = msg.data.data();
  for (int r = 0; r < depth_mm.rows; ++r) {
    const auto* src = depth_mm.ptr<uint16_t>(r);
    for (int c = 0; c < depth_mm.cols; ++c, dst += 2) {
      dst[0] = static_cast<uint8_t>(src[c] & 0xff);
      dst[1] = static_cast<uint8_t>(src[c] >> 8);
    }
  }
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

}  // namespace ivoa
