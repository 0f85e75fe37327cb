#pragma once
// The registry of default LCM channel names. Every process takes these as
// defaults and lets a flag override them. One message type per channel.
#include <string_view>

namespace ivoa::channels {

inline constexpr std::string_view kStereoImages = "STEREO_IMAGES";  // ivoa.stereo_image_t
inline constexpr std::string_view kDepthImage = "DEPTH_IMAGE";      // ivoa.depth_image_t
inline constexpr std::string_view kDepthColor = "DEPTH_COLOR";  // ivoa.image_t (depth sensor's colour camera, optional)
inline constexpr std::string_view kRigCalibration = "RIG_CALIBRATION";            // ivoa.rig_calibration_t
inline constexpr std::string_view kObstaclesStereo = "OBSTACLES_STEREO";          // ivoa.obstacle_grid_t
inline constexpr std::string_view kObstaclesDepth = "OBSTACLES_DEPTH";            // ivoa.obstacle_grid_t
inline constexpr std::string_view kIntrospectionLabels = "INTROSPECTION_LABELS";  // ivoa.introspection_labels_t
inline constexpr std::string_view kIntrospection = "INTROSPECTION";               // ivoa.introspection_t
inline constexpr std::string_view kProcessStatus = "PROCESS_STATUS";              // ivoa.process_status_t
inline constexpr std::string_view kSimGroundTruth = "SIM_GROUND_TRUTH";  // ivoa.sim_ground_truth_t (simulator only)

// LCM 1.3.1 rejects longer names on udpm but not on memq, so unit tests on
// memq would not notice: check it at compile time.
inline constexpr std::size_t kMaxChannelLength = 63;
constexpr bool valid_channel_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxChannelLength) return false;
  for (char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}
static_assert(valid_channel_name(kStereoImages) && valid_channel_name(kDepthImage) && valid_channel_name(kDepthColor) &&
              valid_channel_name(kRigCalibration) && valid_channel_name(kObstaclesStereo) &&
              valid_channel_name(kObstaclesDepth) && valid_channel_name(kIntrospectionLabels) &&
              valid_channel_name(kIntrospection) && valid_channel_name(kProcessStatus) &&
              valid_channel_name(kSimGroundTruth));

}  // namespace ivoa::channels
