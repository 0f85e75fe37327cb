#pragma once
// Whether a frame OpenNI2 hands over holds the image it claims. A damaged
// .oni recording can claim a mode larger than its frames' data: wrapping
// the buffer as the claimed image read past its end (SIGSEGV, or garbage
// published as depth).
#include <string>

namespace ivoa::openni2_kinect {

// Why a width x height frame of bytes_per_pixel, its rows stride_bytes
// apart, cannot be read from data_bytes of buffer; "" if it can.
std::string frame_buffer_error(int width, int height, int stride_bytes, int bytes_per_pixel, int data_bytes);

}  // namespace ivoa::openni2_kinect
