#include "ivoa/openni2_kinect/frame_buffer.hpp"

#include <cstdint>

#include <fmt/format.h>

#include "ivoa/core/image_convert.hpp"

namespace ivoa::openni2_kinect {

std::string frame_buffer_error(int width, int height, int stride_bytes, int bytes_per_pixel, int data_bytes) {
  if (width <= 0 || height <= 0) return fmt::format("a {}x{} frame", width, height);
  if (int64_t{width} * height > kMaxImagePixels)
    return fmt::format("a {}x{} frame, larger than any image ({} pixels at most)", width, height, kMaxImagePixels);
  const int64_t row_bytes = int64_t{width} * bytes_per_pixel;
  if (stride_bytes < row_bytes)
    return fmt::format("{}x{} frame with rows {} bytes apart, too close for {} bytes a row", width, height,
                       stride_bytes, row_bytes);
  const int64_t needed = int64_t{height - 1} * stride_bytes + row_bytes;
  if (data_bytes < needed)
    return fmt::format("{}x{} frame in {} bytes of data, not the {} it needs", width, height, data_bytes, needed);
  return "";
}

}  // namespace ivoa::openni2_kinect
