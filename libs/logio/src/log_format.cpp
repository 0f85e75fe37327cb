#include "ivoa/logio/log_format.hpp"

namespace ivoa::logio {
namespace {

template <class T>
void put_be(uint8_t* out, T value) {
  auto v = static_cast<uint64_t>(value);
  for (size_t i = sizeof(T); i-- > 0;) {
    out[i] = static_cast<uint8_t>(v & 0xFF);
    v >>= 8;
  }
}

template <class T>
T get_be(const uint8_t* in) {
  uint64_t v = 0;
  for (size_t i = 0; i < sizeof(T); ++i) v = (v << 8) | in[i];
  return static_cast<T>(v);
}

}  // namespace

std::array<uint8_t, kEventHeaderBytes> encode_header(const EventHeader& header) {
  std::array<uint8_t, kEventHeaderBytes> out{};
  put_be(out.data(), header.sync);
  put_be(out.data() + 4, header.event_number);
  put_be(out.data() + 12, header.timestamp);
  put_be(out.data() + 20, header.channel_bytes);
  put_be(out.data() + 24, header.data_bytes);
  return out;
}

EventHeader decode_header(const uint8_t* bytes) {
  EventHeader h;
  h.sync = get_be<uint32_t>(bytes);
  h.event_number = get_be<int64_t>(bytes + 4);
  h.timestamp = get_be<int64_t>(bytes + 12);
  h.channel_bytes = get_be<uint32_t>(bytes + 20);
  h.data_bytes = get_be<uint32_t>(bytes + 24);
  return h;
}

}  // namespace ivoa::logio
