#include "ivoa/aravis_stereo/aravis_buffer.hpp"

#include <cstdio>
#include <cstring>
#include <string>

#include "ivoa/aravis_stereo/pixel_formats.hpp"

namespace ivoa::aravis_stereo {
namespace {

std::string hex(uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof(text), "0x%08x", value);
  return text;
}

FrameResult incomplete(uint64_t frame_id, const std::string& why) {
  FrameResult r;
  r.complete = false;
  r.problem = "frame " + std::to_string(frame_id) + ": " + why;
  return r;
}

}  // namespace

const char* buffer_status_name(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS: return "complete";
    case ARV_BUFFER_STATUS_CLEARED: return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT: return "timed out before all packets arrived";
    case ARV_BUFFER_STATUS_MISSING_PACKETS: return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID: return "packet with a wrong id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH: return "image larger than the buffer";
    case ARV_BUFFER_STATUS_FILLING: return "still filling";
    case ARV_BUFFER_STATUS_ABORTED: return "aborted";
    default: return "unknown status";
  }
}

bool buffer_was_filled(ArvBuffer* buffer) { return arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_CLEARED; }

FrameResult buffer_to_frame(ArvBuffer* buffer, Side side) {
  const uint64_t frame_id = arv_buffer_get_frame_id(buffer);
  const ArvBufferStatus status = arv_buffer_get_status(buffer);
  if (status != ARV_BUFFER_STATUS_SUCCESS) return incomplete(frame_id, buffer_status_name(status));
  const ArvBufferPayloadType payload = arv_buffer_get_payload_type(buffer);
  if (payload != ARV_BUFFER_PAYLOAD_TYPE_IMAGE && payload != ARV_BUFFER_PAYLOAD_TYPE_EXTENDED_CHUNK_DATA)
    return incomplete(frame_id, "payload is not an image (type " + std::to_string(payload) + ")");

  const ArvPixelFormat arv_format = arv_buffer_get_image_pixel_format(buffer);
  const auto format = ivoa_pixelformat_from_genicam(arv_format);
  if (!format) return incomplete(frame_id, "unsupported pixel format " + hex(arv_format));

  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  const int bytes_per_pixel = static_cast<int>(ARV_PIXEL_FORMAT_BIT_PER_PIXEL(arv_format) / 8);
  int padding_x = 0, padding_y = 0;
  arv_buffer_get_image_padding(buffer, &padding_x, &padding_y);
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(bytes_per_pixel);
  const size_t stride = row_bytes + static_cast<size_t>(padding_x);
  size_t size = 0;
  const auto* pixels = static_cast<const uint8_t*>(arv_buffer_get_image_data(buffer, &size));
  if (width <= 0 || height <= 0 || pixels == nullptr || size < stride * static_cast<size_t>(height - 1) + row_bytes)
    return incomplete(frame_id, std::to_string(width) + "x" + std::to_string(height) + " image but " +
                                    std::to_string(size) + " bytes of data");

  FrameResult r;
  r.complete = true;
  CameraFrame& f = r.frame;
  f.side = side;
  f.frame_id = frame_id;
  f.width = width;
  f.height = height;
  f.pixelformat = *format;
  f.utime = static_cast<int64_t>(arv_buffer_get_system_timestamp(buffer) / 1000);
  f.device_time_us = static_cast<int64_t>(arv_buffer_get_timestamp(buffer) / 1000);
  f.pairing_time_us = f.utime;
  f.data.resize(row_bytes * static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) std::memcpy(f.data.data() + row_bytes * y, pixels + stride * y, row_bytes);
  return r;
}

}  // namespace ivoa::aravis_stereo
