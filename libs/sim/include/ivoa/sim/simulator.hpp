#pragma once
// The simulated robot's sensors: renders, for a robot pose in a scene, the
// raw stereo pair, the depth image and per-pixel ground truth for the left
// camera. Single-threaded and deterministic: the same scene, pose and frame
// index always give bit-identical images.
#include <cstdint>
#include <memory>

#include <opencv2/core.hpp>

#include "ivoa/core/calibration.hpp"
#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/scene.hpp"
#include "ivoa/sim/sensors.hpp"
#include "ivoa/sim/sim_rig.hpp"
#include "ivoa/sim/truth.hpp"

namespace ivoa::sim {

struct SimFrame {
  cv::Mat left, right;      // CV_8UC3 BGR raw (distorted), rig size (960x600)
  cv::Mat depth_mm;         // CV_16UC1 depth sensor image, 0 = invalid
  cv::Mat truth_depth;      // CV_32FC1 left camera planar depth in metres, +inf where nothing
  cv::Mat truth_surface;    // CV_8UC1 sim_ground_truth_t::SURFACE_*
  cv::Mat truth_phenomena;  // CV_8UC1 OR of sim_ground_truth_t::PHENOMENON_*
  double exposure_ms = 0;   // the cameras' exposure time for this frame
  double gain = 1;          // and analog gain
  // Where render() spent its time (milliseconds of this thread's CPU time).
  struct Timings {
    double left_ms = 0, right_ms = 0;  // ray casting and shading per camera
    double sensor_ms = 0;              // exposure, blur, noise, demosaic, truth flags
    double depth_ms = 0;               // depth sensor: ray casting and its model
  } timings;
};

struct SimulatorConfig {
  RigCalibration rig = make_sim_rig();
  CameraSensorConfig camera;
  DepthSensorConfig depth;
  bool render_depth = true;
  // Which realisation of the sensor noise (camera and depth) frames get:
  // 0 keys it by the frame index alone; another value gives every frame
  // other noise with the same scene, poses and exposure, e.g. to measure how
  // repeatable the labels are under noise alone.
  uint64_t noise_seed = 0;
  // false: every pixel tests every solid (the brute-force baseline the
  // benchmark compares against); the images are identical either way.
  bool use_acceleration = true;
};

// Poses of the sensors for one frame: the depth sensor may be sampled a few
// milliseconds apart from the stereo pair. `motion` blurs the images.
struct RenderRequest {
  Pose2D stereo_pose;
  Pose2D depth_pose;
  uint64_t frame_index = 0;  // seeds the sensor noise (with SimulatorConfig::noise_seed)
  Twist2D motion;            // robot velocity during the exposure
};

class Simulator {
 public:
  explicit Simulator(Scene scene, SimulatorConfig config = {});
  ~Simulator();
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;

  const RigCalibration& rig() const;
  const Scene& scene() const;
  const SimulatorConfig& config() const;

  SimFrame render(const Pose2D& robot_pose, uint64_t frame_index) const;
  SimFrame render(const RenderRequest& request) const;

  // Footprint occupancy at robot-frame ground point (x, y): see truth.hpp.
  TruthState footprint_truth(const Pose2D& robot_pose, double x, double y, double radius,
                             double min_height = 0.05) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ivoa::sim
