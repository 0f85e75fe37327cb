#include "ivoa/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>

#include "camera_rays.hpp"
#include "camera_sensor.hpp"
#include "depth_sensor.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "rng.hpp"
#include "tracer.hpp"

namespace ivoa::sim {

using detail::CameraRays;
using detail::Ranged;
using detail::SceneData;
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

double thread_cpu_ms() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Signal-to-noise below which a pixel counts as noise-dominated: texture of
// ~10 % contrast drowns in the noise.
constexpr double kLowLightSnr = 10.0;
// Specular part brighter than this fraction of full scale counts as glare.
constexpr double kGlareLevel = 0.5;

// Per-thread scratch reused across frames (every entry is written before it is read).
struct Scratch {
  std::vector<Rgbf> left_radiance, right_radiance;
  std::vector<float> specular;  // the left camera's specular radiance (glare)
  std::vector<Shaded> shaded;
};

// Traces the left camera: its radiance and specular part into `scratch`,
// the per-pixel ground truth into `f`.
void shade_left(const SceneData& data, const CameraRays& rays, const Pose2D& pose, bool accel, Scratch& scratch,
                SimFrame& f) {
  const int w = rays.width();
  const Tracer tracer(data, rays, pose, accel);
  tracer.shade_image(scratch.shaded.data(), [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      float* depth = f.truth_depth.ptr<float>(y);
      uint8_t* surface = f.truth_surface.ptr<uint8_t>(y);
      uint8_t* phenomena = f.truth_phenomena.ptr<uint8_t>(y);
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        const Shaded& sh = scratch.shaded[i];
        scratch.left_radiance[i] = sh.radiance;
        scratch.specular[i] = sh.specular;
        depth[x] = sh.depth;
        surface[x] = sh.surface;
        phenomena[x] = sh.phenomena;
      }
    }
  });
}

void shade_right(const SceneData& data, const CameraRays& rays, const Pose2D& pose, bool accel, Scratch& scratch) {
  const Tracer tracer(data, rays, pose, accel);
  const int rw = rays.width();
  tracer.shade_image(scratch.shaded.data(), [&](int y0, int y1) {
    const size_t end = static_cast<size_t>(y1) * rw;
    for (size_t i = static_cast<size_t>(y0) * rw; i < end; ++i) scratch.right_radiance[i] = scratch.shaded[i].radiance;
  });
}

// Flags the phenomena that depend on the exposure: clipping, noise-dominated
// pixels, glare. SNR = S / sqrt(S + read^2) < k <=> S^2 < k^2 (S + read^2) for S >= 0.
void flag_exposure_phenomena(const Scratch& scratch, const detail::Exposure& exposure, const CameraSensorConfig& cam,
                             const cv::Mat& saturated, cv::Mat& phenomena) {
  const float e_per_unit = static_cast<float>(exposure.electrons_per_unit);
  const float read2 = static_cast<float>(cam.read_noise * cam.read_noise);
  const float k2 = static_cast<float>(kLowLightSnr * kLowLightSnr);
  const float glare_radiance = static_cast<float>(kGlareLevel * cam.full_well / exposure.gain) / e_per_unit;
  for (int y = 0; y < phenomena.rows; ++y) {
    uint8_t* flags = phenomena.ptr<uint8_t>(y);
    const uint8_t* clipped = saturated.ptr<uint8_t>(y);
    for (int x = 0; x < phenomena.cols; ++x) {
      const size_t i = static_cast<size_t>(y) * phenomena.cols + x;
      const float signal = scratch.left_radiance[i].luminance() * e_per_unit;
      if (clipped[x]) flags[x] |= GT::PHENOMENON_SATURATED;
      else if (signal * signal < k2 * (signal + read2)) flags[x] |= GT::PHENOMENON_LOW_LIGHT;
      if (scratch.specular[i] > glare_radiance) flags[x] |= GT::PHENOMENON_GLARE;
    }
  }
}

// The depth sensor's image: ranges traced from its pose through its model.
cv::Mat render_depth(const SceneData& data, const CameraRays& rays, const SimulatorConfig& config, const Pose2D& pose,
                     uint64_t noise_key) {
  const Tracer tracer(data, rays, pose, config.use_acceleration);
  thread_local std::vector<Ranged> ranged;
  ranged.resize(static_cast<size_t>(rays.width()) * rays.height());
  for (size_t i = 0; i < ranged.size(); ++i) ranged[i] = tracer.range(static_cast<int>(i));
  const auto& rig = config.rig;
  return detail::depth_image(ranged, rays.width(), rays.height(), rig.depth.K(0, 0), rig.depth_min_range,
                             rig.depth_max_range, config.depth, noise_key);
}

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
  SimFrame f;
  double clock = thread_cpu_ms();
  auto lap = [&clock](double& into) {
    const double now = thread_cpu_ms();
    into = now - clock;
    clock = now;
  };
  f.truth_depth.create(h, w, CV_32FC1);
  f.truth_surface.create(h, w, CV_8UC1);
  f.truth_phenomena.create(h, w, CV_8UC1);

  thread_local Scratch scratch;
  const size_t n = static_cast<size_t>(w) * h;
  scratch.left_radiance.resize(n);
  scratch.right_radiance.resize(static_cast<size_t>(s.right.width()) * s.right.height());
  scratch.specular.resize(n);
  scratch.shaded.resize(std::max(n, scratch.right_radiance.size()));
  shade_left(data, s.left, req.stereo_pose, accel, scratch, f);
  lap(f.timings.left_ms);
  shade_right(data, s.right, req.stereo_pose, accel, scratch);
  lap(f.timings.right_ms);

  const detail::Exposure exposure = detail::auto_exposure(scratch.left_radiance, cam, data.max_exposure_scale);
  f.exposure_ms = exposure.time_ms;
  f.gain = exposure.gain;
  // Turning smears the image along rows by yaw rate x exposure x focal length.
  const double smear = std::abs(req.motion.omega) * exposure.time_ms * 1e-3 * s.config.rig.left.K(0, 0);
  // Seed 0 keeps the noise of earlier recordings bit-identical.
  const uint64_t noise_key =
      s.config.noise_seed == 0 ? req.frame_index : hash_combine(req.frame_index, s.config.noise_seed);
  const auto left_image = detail::expose(scratch.left_radiance, w, h, exposure, 1.0, cam, noise_key, 0, smear, true);
  const auto right_image = detail::expose(scratch.right_radiance, s.right.width(), s.right.height(), exposure,
                                          cam.right_sensitivity, cam, noise_key, 1, smear, false);
  f.left = left_image.bgr;
  f.right = right_image.bgr;
  flag_exposure_phenomena(scratch, exposure, cam, left_image.saturated, f.truth_phenomena);
  lap(f.timings.sensor_ms);

  f.depth_mm = s.config.render_depth ? render_depth(data, s.depth, s.config, req.depth_pose, noise_key)
                                     : cv::Mat::zeros(s.depth.height(), s.depth.width(), CV_16UC1);
  lap(f.timings.depth_ms);
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
