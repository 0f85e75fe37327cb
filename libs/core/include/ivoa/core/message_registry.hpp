#pragma once
// Every ivoa message type with its LCM fingerprint, so tools that see raw
// payloads (logger, stats, dataset) can tell what a channel carries.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace ivoa {

struct MessageTypeInfo {
  std::string_view name;                           // "ivoa.image_t"
  int64_t fingerprint;                             // the first 8 bytes of every encoded message
  bool (*decodes)(const void* data, size_t size);  // whether a payload decodes as this type
};

const std::vector<MessageTypeInfo>& message_types();

// The fingerprint an encoded payload starts with; empty if it is too short.
std::optional<int64_t> payload_fingerprint(const void* data, size_t size);
// "ivoa.stereo_image_t", or empty for a payload of another or unknown type.
std::optional<std::string_view> payload_type_name(const void* data, size_t size);
// True for a payload with an ivoa type's fingerprint that does not decode
// as that type (truncated or damaged inside); false otherwise, payloads of
// unknown types included.
bool ivoa_payload_damaged(const void* data, size_t size);

// Whether the type carries a seq (stereo and depth images, after utime).
bool type_has_seq(std::string_view type_name);
// Types every process publishes on one channel (the PROCESS_STATUS
// heartbeats): their utimes interleave by sender, so a channel's utime
// order says nothing about them.
bool type_has_many_senders(std::string_view type_name);
// Every ivoa type starts with utime; stereo and depth images follow it with
// seq. Read straight from the payload of an ivoa message (no decoding);
// empty if the payload is too short or the type has no such field.
std::optional<int64_t> payload_utime(const void* data, size_t size);
std::optional<int64_t> payload_seq(std::string_view type_name, const void* data, size_t size);

}  // namespace ivoa
