#include "ivoa/core/message_registry.hpp"

#include "ivoa/core/message_counts.hpp"

namespace ivoa {
namespace {

int64_t read_be64(const uint8_t* b) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];  // LCM encodes big-endian
  return static_cast<int64_t>(v);
}

}  // namespace

const std::vector<MessageTypeInfo>& message_types() {
  static const std::vector<MessageTypeInfo> types = {
      {"ivoa.image_t", image_t::getHash()},
      {"ivoa.stereo_image_t", stereo_image_t::getHash()},
      {"ivoa.depth_image_t", depth_image_t::getHash()},
      {"ivoa.camera_intrinsics_t", camera_intrinsics_t::getHash()},
      {"ivoa.rig_calibration_t", rig_calibration_t::getHash()},
      {"ivoa.obstacle_grid_t", obstacle_grid_t::getHash()},
      {"ivoa.introspection_labels_t", introspection_labels_t::getHash()},
      {"ivoa.introspection_t", introspection_t::getHash()},
      {"ivoa.process_status_t", process_status_t::getHash()},
      {"ivoa.sim_ground_truth_t", sim_ground_truth_t::getHash()},
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

std::optional<std::string_view> payload_type_name(const void* data, size_t size) {
  const auto fp = payload_fingerprint(data, size);
  if (!fp) return std::nullopt;
  for (const auto& t : message_types())
    if (t.fingerprint == *fp) return t.name;
  return std::nullopt;
}

}  // namespace ivoa
