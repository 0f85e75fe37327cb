#include "ivoa/core/message_registry.hpp"

#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/message_decode.hpp"

namespace ivoa {
namespace {

int64_t read_be64(const uint8_t* b) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];  // LCM encodes big-endian
  return static_cast<int64_t>(v);
}

// One message per type and thread, reused: its arrays keep their capacity,
// so checking a log's images does not allocate (and fault in) each anew.
template <class Msg>
bool decodes_as(const void* data, size_t size) {
  thread_local Msg msg;
  return decode_message(msg, data, size);
}

template <class Msg>
MessageTypeInfo info_of() {
  static const std::string name = std::string("ivoa.") + Msg::getTypeName();
  return {name, Msg::getHash(), &decodes_as<Msg>};
}

}  // namespace

const std::vector<MessageTypeInfo>& message_types() {
  static const std::vector<MessageTypeInfo> types = {
      info_of<image_t>(),
      info_of<stereo_image_t>(),
      info_of<depth_image_t>(),
      info_of<camera_intrinsics_t>(),
      info_of<rig_calibration_t>(),
      info_of<obstacle_grid_t>(),
      info_of<introspection_labels_t>(),
      info_of<introspection_t>(),
      info_of<process_status_t>(),
      info_of<sim_ground_truth_t>(),
  };
  return types;
}

std::optional<int64_t> payload_fingerprint(const void* data, size_t size) {
  if (size < 8) return std::nullopt;
  return read_be64(static_cast<const uint8_t*>(data));
}

std::optional<int64_t> payload_utime(const void* data, size_t size) {
  if (size < 16) return std::nullopt;
  return read_be64(static_cast<const uint8_t*>(data) + 8);
}

bool type_has_seq(std::string_view type_name) {
  return type_name == "ivoa.stereo_image_t" || type_name == "ivoa.depth_image_t";
}

bool type_has_many_senders(std::string_view type_name) { return type_name == "ivoa.process_status_t"; }

std::optional<int64_t> payload_seq(std::string_view type_name, const void* data, size_t size) {
  if (!type_has_seq(type_name) || size < 24) return std::nullopt;
  return read_be64(static_cast<const uint8_t*>(data) + 16);
}

namespace {

const MessageTypeInfo* type_of(const void* data, size_t size) {
  const auto fp = payload_fingerprint(data, size);
  if (!fp) return nullptr;
  for (const auto& t : message_types())
    if (t.fingerprint == *fp) return &t;
  return nullptr;
}

}  // namespace

bool ivoa_payload_damaged(const void* data, size_t size) {
  const MessageTypeInfo* type = type_of(data, size);
  return type != nullptr && !type->decodes(data, size);
}

std::optional<std::string_view> payload_type_name(const void* data, size_t size) {
  const MessageTypeInfo* type = type_of(data, size);
  if (type == nullptr) return std::nullopt;
  return type->name;
}

}  // namespace ivoa
