#include "ivoa/sim/simulator.hpp"

#include <cmath>
#include <limits>

#include "camera_rays.hpp"
#include "camera_sensor.hpp"
#include "depth_sensor.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "tracer.hpp"

namespace ivoa::sim {

using detail::CameraRays;
using detail::Ranged;
using detail::Shaded;
using detail::Tracer;
using GT = sim_ground_truth_t;

struct Simulator::Impl {
  Impl(Scene s, SimulatorConfig c)
      : scene(std::move(s)),
        config(std::move(c)),
        geometry(config.rig),
        left_rays(detail::shared_camera_rays(geometry.left)),
        right_rays(detail::shared_camera_rays(geometry.right)),
        depth_rays(detail::shared_camera_rays(geometry.depth)),
        left(*left_rays),
        right(*right_rays),
        depth(*depth_rays) {}
  Scene scene;
  SimulatorConfig config;
  RigGeometry geometry;
  std::shared_ptr<const CameraRays> left_rays, right_rays, depth_rays;
  const CameraRays &left, &right, &depth;
};

namespace {

// Signal-to-noise below which a pixel counts as noise-dominated: texture of
// ~10 % contrast drowns in the noise.
constexpr double kLowLightSnr = 10.0;
// Specular part brighter than this fraction of full scale counts as glare.
constexpr double kGlareLevel = 0.5;

}  // namespace

Simulator::Simulator(Scene scene, SimulatorConfig config) {
  validate(config.rig, "simulator rig");
  impl_ = std::make_unique<Impl>(std::move(scene), std::move(config));
}

Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

const RigCalibration& Simulator::rig() const { return impl_->config.rig; }
const Scene& Simulator::scene() const { return impl_->scene; }
const SimulatorConfig& Simulator::config() const { return impl_->config; }

SimFrame Simulator::render(const Pose2D& robot_pose, uint64_t frame_index) const {
  RenderRequest request;
  request.stereo_pose = request.depth_pose = robot_pose;
  request.frame_index = frame_index;
  return render(request);
}

SimFrame Simulator::render(const RenderRequest& req) const {
  const Impl& s = *impl_;
  const auto& data = s.scene.data();
  const auto& cam = s.config.camera;
  const bool accel = s.config.use_acceleration;
  const int w = s.left.width(), h = s.left.height();
  const size_t n = static_cast<size_t>(w) * h;
  SimFrame f;
  f.truth_depth.create(h, w, CV_32FC1);
  f.truth_surface.create(h, w, CV_8UC1);
  f.truth_phenomena.create(h, w, CV_8UC1);

  std::vector<Rgbf> left_radiance(n), right_radiance(static_cast<size_t>(s.right.width()) * s.right.height());
  std::vector<float> specular(n);
  {
    const Tracer tracer(data, s.left, req.stereo_pose, accel);
    std::vector<Shaded> row(static_cast<size_t>(w));
    for (int y = 0; y < h; ++y) {
      tracer.shade_row(y, row.data());
      float* depth = f.truth_depth.ptr<float>(y);
      uint8_t* surface = f.truth_surface.ptr<uint8_t>(y);
      uint8_t* phenomena = f.truth_phenomena.ptr<uint8_t>(y);
      for (int x = 0; x < w; ++x) {
        const Shaded& sh = row[static_cast<size_t>(x)];
        const size_t i = static_cast<size_t>(y) * w + x;
        left_radiance[i] = sh.radiance;
        specular[i] = sh.specular;
        depth[x] = sh.depth;
        surface[x] = sh.surface;
        phenomena[x] = sh.phenomena;
      }
    }
  }
  {
    const Tracer tracer(data, s.right, req.stereo_pose, accel);
    const int rw = s.right.width();
    std::vector<Shaded> row(static_cast<size_t>(rw));
    for (int y = 0; y < s.right.height(); ++y) {
      tracer.shade_row(y, row.data());
      for (int x = 0; x < rw; ++x) right_radiance[static_cast<size_t>(y) * rw + x] = row[static_cast<size_t>(x)].radiance;
    }
  }

  const detail::Exposure exposure = detail::auto_exposure(left_radiance, cam, data.max_exposure_scale);
  f.exposure_ms = exposure.time_ms;
  f.gain = exposure.gain;
  // Turning smears the image along rows by yaw rate x exposure x focal length.
  const double smear = std::abs(req.motion.omega) * exposure.time_ms * 1e-3 * s.config.rig.left.K(0, 0);
  const auto left_image = detail::expose(left_radiance, w, h, exposure, 1.0, cam, req.frame_index, 0, smear);
  const auto right_image = detail::expose(right_radiance, s.right.width(), s.right.height(), exposure,
                                          cam.right_sensitivity, cam, req.frame_index, 1, smear);
  f.left = left_image.bgr;
  f.right = right_image.bgr;

  // Phenomena that depend on the exposure: clipping, noise-dominated pixels, glare.
  const double e_per_unit = exposure.electrons_per_unit;
  const double read2 = cam.read_noise * cam.read_noise;
  const double full_scale = cam.full_well / exposure.gain;
  for (int y = 0; y < h; ++y) {
    uint8_t* phenomena = f.truth_phenomena.ptr<uint8_t>(y);
    const uint8_t* saturated = left_image.saturated.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const double signal = left_radiance[i].luminance() * e_per_unit;
      if (saturated[x]) phenomena[x] |= GT::PHENOMENON_SATURATED;
      else if (signal / std::sqrt(signal + read2) < kLowLightSnr) phenomena[x] |= GT::PHENOMENON_LOW_LIGHT;
      if (specular[i] * e_per_unit > kGlareLevel * full_scale) phenomena[x] |= GT::PHENOMENON_GLARE;
    }
  }

  if (s.config.render_depth) {
    const Tracer tracer(data, s.depth, req.depth_pose, accel);
    std::vector<Ranged> ranged(static_cast<size_t>(s.depth.width()) * s.depth.height());
    for (size_t i = 0; i < ranged.size(); ++i) ranged[i] = tracer.range(static_cast<int>(i));
    const auto& rig = s.config.rig;
    f.depth_mm = detail::depth_image(ranged, s.depth.width(), s.depth.height(), rig.depth.K(0, 0), rig.depth_min_range,
                                     rig.depth_max_range, s.config.depth, req.frame_index);
  } else {
    f.depth_mm = cv::Mat::zeros(s.depth.height(), s.depth.width(), CV_16UC1);
  }
  return f;
}

TruthState Simulator::footprint_truth(const Pose2D& robot_pose, double x, double y, double radius,
                                      double min_height) const {
  TruthQuery q;
  q.radius = radius;
  q.min_height = min_height;
  return impl_->scene.truth_at(robot_to_world(robot_pose, x, y), q);
}

}  // namespace ivoa::sim
