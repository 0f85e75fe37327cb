#pragma once
// The LCM log file format (lcm_notes.md §2.4; what lcm-logger writes and
// lcm-logplayer reads): a sequence of events, each a 28-byte big-endian
// header (sync word, event number, timestamp, channel length, data length)
// followed by the channel name (no terminator) and the encoded message.
#include <array>
#include <cstddef>
#include <cstdint>

namespace ivoa::logio {

inline constexpr uint32_t kSyncWord = 0xEDA1DA01;
inline constexpr uint8_t kSyncBytes[4] = {0xED, 0xA1, 0xDA, 0x01};  // kSyncWord as it is in the file
inline constexpr size_t kEventHeaderBytes = 28;
// Limits a plausible header must respect; larger values mean corruption.
// LCM itself refuses messages over 256 MB and channel names over 63 bytes
// on udpm; other transports allow somewhat longer names.
inline constexpr uint32_t kMaxChannelBytes = 256;
inline constexpr uint32_t kMaxDataBytes = 1u << 28;

struct EventHeader {
  uint32_t sync = kSyncWord;
  int64_t event_number = 0;
  int64_t timestamp = 0;  // microseconds since the epoch (the logger's receive time)
  uint32_t channel_bytes = 0;
  uint32_t data_bytes = 0;

  uint64_t event_bytes() const { return kEventHeaderBytes + uint64_t{channel_bytes} + data_bytes; }
};

std::array<uint8_t, kEventHeaderBytes> encode_header(const EventHeader& header);
EventHeader decode_header(const uint8_t* bytes);

}  // namespace ivoa::logio
