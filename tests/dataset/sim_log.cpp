#include "sim_log.hpp"

#include "ivoa/core/bus.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/sim/messages.hpp"
#include "ivoa/sim/trajectory.hpp"
#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::test {

SimLog write_sim_log(const std::string& path, const std::string& scene_file, uint64_t seed, int frames,
                     const std::function<void(Bus&, const SimLogFrame&, const sim::SimFrame&)>& extra) {
  const sim::Scene scene = sim::generate_scene(sim::load_scene_spec(scene_file), seed);
  const sim::Simulator simulator(scene);
  sim::Trajectory trajectory(scene, seed);
  Bus bus("file://" + path + "?mode=w");
  SimLog log;
  log.rig = simulator.rig();
  const int64_t start = 1'700'000'000'000'000;
  for (int f = 0; f < frames; ++f) {
    SimLogFrame lf;
    lf.index = static_cast<uint64_t>(f);
    lf.utime = start + f * 200'000;  // 5 Hz: a new view every frame
    lf.depth_utime = lf.utime + 4'000;
    lf.pose = trajectory.pose_at(0.2 * f);
    const sim::SimFrame frame = simulator.render(lf.pose, lf.index);
    if (f % 5 == 0) {
      rig_calibration_t calibration = to_message(simulator.rig(), lf.utime);
      bus.publish(channels::kRigCalibration, calibration);
    }
    stereo_image_t stereo = sim::make_stereo_message(frame, lf.utime, f, image_t::PIXEL_FORMAT_BGR);
    bus.publish(channels::kStereoImages, stereo);
    depth_image_t depth = sim::make_depth_message(frame, simulator.rig(), lf.depth_utime, f);
    bus.publish(channels::kDepthImage, depth);
    sim_ground_truth_t truth = sim::make_truth_message(frame, scene, lf.pose, lf.utime, f);
    bus.publish(channels::kSimGroundTruth, truth);
    if (extra) extra(bus, lf, frame);
    log.frames.push_back(lf);
  }
  return log;
}

}  // namespace ivoa::test
