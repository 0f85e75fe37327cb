#include "camera_rays.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

namespace ivoa::sim::detail {

CameraRays::CameraRays(const CameraModel& camera, double bin_pixels)
    : width_(camera.intrinsics().width),
      height_(camera.intrinsics().height),
      origin_(camera.origin()),
      pixel_angle_(static_cast<float>(1.0 / camera.intrinsics().K(0, 0))) {
  rays_.resize(static_cast<size_t>(width_) * height_);
  // The optical axis in the robot frame: the principal point undistorts to (0, 0).
  const Eigen::Vector2d principal = camera.intrinsics().K.block<2, 1>(0, 2);
  const Eigen::Vector3d z_axis = (camera.unproject(principal, 1.0) - camera.unproject(principal, 0.0)).normalized();
  std::vector<double> azimuths(rays_.size());
  double az_lo = 1e9, az_hi = -1e9;
  const double eps = 1e-7;
  for (int v = 0; v < height_; ++v)
    for (int u = 0; u < width_; ++u) {
      const Eigen::Vector3d d = camera.ray(Eigen::Vector2d(u, v));
      PixelRay& r = rays_[static_cast<size_t>(v) * width_ + u];
      const double h = std::max(eps, std::hypot(d.x(), d.y()));
      r.ux = static_cast<float>(d.x() / h);
      r.uy = static_cast<float>(d.y() / h);
      double slope = d.z() / h;
      if (std::abs(slope) < eps) slope = slope < 0 ? -eps : eps;
      r.slope = static_cast<float>(slope);
      r.inv_slope = static_cast<float>(1.0 / slope);
      r.len = static_cast<float>(1.0 / h);
      r.inv_len = static_cast<float>(h);
      r.planar = static_cast<float>(d.dot(z_axis) / h);
      if (slope < 0 && origin_.z() > 0) {
        const double s = -origin_.z() / slope;
        r.s_floor = static_cast<float>(s);
        r.floor_x = static_cast<float>(origin_.x() + s * d.x() / h);
        r.floor_y = static_cast<float>(origin_.y() + s * d.y() / h);
        // Pixel footprint on the ground: distance x pixel angle, stretched
        // by the grazing angle (geometric mean of the two axes).
        const double dist = s / h, cos_i = -d.z();
        r.floor_footprint = static_cast<float>(dist * pixel_angle_ / std::sqrt(std::max(cos_i, 0.02)));
      } else {
        r.s_floor = std::numeric_limits<float>::infinity();
      }
      const double az = std::atan2(d.y(), d.x());
      azimuths[static_cast<size_t>(v) * width_ + u] = az;
      az_lo = std::min(az_lo, az);
      az_hi = std::max(az_hi, az);
    }
  bin_width_ = static_cast<float>(bin_pixels * pixel_angle_);
  az_min_ = static_cast<float>(az_lo - 2 * bin_width_);
  num_bins_ = static_cast<int>(std::ceil((az_hi - az_min_) / bin_width_)) + 2;
  for (size_t i = 0; i < rays_.size(); ++i)
    rays_[i].bin =
        static_cast<uint16_t>(std::clamp(static_cast<int>((azimuths[i] - az_min_) / bin_width_), 0, num_bins_ - 1));
}

}  // namespace ivoa::sim::detail

namespace ivoa::sim::detail {

std::shared_ptr<const CameraRays> shared_camera_rays(const CameraModel& camera) {
  std::ostringstream key;
  key.precision(17);
  const auto& in = camera.intrinsics();
  key << in.width << ' ' << in.height;
  for (int i = 0; i < 9; ++i) key << ' ' << in.K(i / 3, i % 3);
  for (double d : in.D) key << ' ' << d;
  const Eigen::Vector3d o = camera.origin();
  const Eigen::Vector3d ax = camera.ray(Eigen::Vector2d(0, 0)),
                        ay = camera.ray(Eigen::Vector2d(in.width - 1, in.height - 1));
  key << ' ' << o.x() << ' ' << o.y() << ' ' << o.z() << ' ' << ax.x() << ' ' << ax.y() << ' ' << ax.z() << ' '
      << ay.x() << ' ' << ay.y() << ' ' << ay.z();
  static std::mutex mutex;
  static std::map<std::string, std::weak_ptr<const CameraRays>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[key.str()];
  if (auto rays = slot.lock()) return rays;
  auto rays = std::make_shared<const CameraRays>(camera);
  slot = rays;
  return rays;
}

}  // namespace ivoa::sim::detail
