#include "ivoa/sim/messages.hpp"

#include "ivoa/core/image_convert.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::sim {

stereo_image_t make_stereo_message(const SimFrame& frame, int64_t utime, int64_t seq, int32_t pixelformat) {
  stereo_image_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.source = kSourceName;
  msg.left = encode_image(frame.left, pixelformat, utime);
  msg.right = encode_image(frame.right, pixelformat, utime);
  return msg;
}

depth_image_t make_depth_message(const SimFrame& frame, const RigCalibration& rig, int64_t utime, int64_t seq) {
  const Eigen::Matrix3d& K = rig.depth.K;
  depth_image_t msg = encode_depth(frame.depth_mm, K(0, 0), K(1, 1), K(0, 2), K(1, 2), utime);
  msg.seq = seq;
  msg.source = kSourceName;
  return msg;
}

sim_ground_truth_t make_truth_message(const SimFrame& frame, const Scene& scene, const Pose2D& pose, int64_t utime,
                                      int64_t seq, bool png) {
  sim_ground_truth_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.scene = scene.name();
  msg.seed = static_cast<int64_t>(scene.seed());
  msg.environment = scene.environment() == Environment::kOutdoor ? "outdoor" : "indoor";
  msg.robot_x = pose.x;
  msg.robot_y = pose.y;
  msg.robot_yaw = pose.yaw;
  const int32_t format =
      png ? static_cast<int32_t>(image_t::PIXEL_FORMAT_PNG) : static_cast<int32_t>(image_t::PIXEL_FORMAT_GRAY);
  msg.surface = encode_image(frame.truth_surface, format, utime);
  msg.phenomena = encode_image(frame.truth_phenomena, format, utime);
  return msg;
}

}  // namespace ivoa::sim
