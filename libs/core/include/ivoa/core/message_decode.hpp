#pragma once
// Decoding an lcm-gen message from bytes that may be damaged. lcm-gen's
// decode() returns < 0 for another type's fingerprint or a short buffer,
// but a damaged length field inside (a string's or an image's size) makes
// it throw instead (std::length_error, std::bad_alloc): from inside an LCM
// handler that would end the process over one bad message.
#include <cstddef>
#include <exception>

namespace ivoa {

// True if `data` decodes as Msg; false (msg unspecified) otherwise.
template <class Msg>
bool decode_message(Msg& msg, const void* data, size_t size) noexcept {
  try {
    return msg.decode(data, 0, static_cast<int>(size)) >= 0;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace ivoa
