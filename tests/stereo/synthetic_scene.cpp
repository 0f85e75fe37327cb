#include "synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core/utility.hpp>

namespace ivoa::test {
namespace {

double hash01(int64_t ix, int64_t iy, uint32_t seed) {
  uint64_t h = static_cast<uint64_t>(ix) * 0x9E3779B97F4A7C15ULL ^ static_cast<uint64_t>(iy) * 0xC2B2AE3D27D4EB4FULL ^
               (static_cast<uint64_t>(seed) << 32);
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBULL;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(1ULL << 53);
}

double value_noise(double u, double v, double cell, uint32_t seed) {
  const double x = u / cell, y = v / cell;
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  auto smooth = [](double t) { return t * t * (3 - 2 * t); };
  const double sx = smooth(x - fx), sy = smooth(y - fy);
  const double top = (1 - sx) * hash01(ix, iy, seed) + sx * hash01(ix + 1, iy, seed);
  const double bottom = (1 - sx) * hash01(ix, iy + 1, seed) + sx * hash01(ix + 1, iy + 1, seed);
  return (1 - sy) * top + sy * bottom;
}

// World-anchored texture, grey level around `mean` (carpet/concrete-like
// blotches from 1 cm to 10 cm).
double texture(double u, double v, uint32_t seed, double mean, double scale = 1.0) {
  const double t = 0.45 * value_noise(u, v, 0.012 * scale, seed) + 0.35 * value_noise(u, v, 0.035 * scale, seed + 1) +
                   0.20 * value_noise(u, v, 0.10 * scale, seed + 2);
  return mean + (t - 0.5) * 2.0 * 90.0;
}

struct Ray {
  Eigen::Vector3d origin, dir;
};

// Nearest box hit along the ray (t > eps); returns the grey level seen.
bool hit_boxes(const SyntheticScene& scene, const Ray& ray, double& t_best, double& gray) {
  bool hit = false;
  for (const SceneBox& box : scene.boxes) {
    double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(ray.dir[a]) < 1e-12) {
        if (ray.origin[a] < box.min[a] || ray.origin[a] > box.max[a]) t_near = t_far + 1;
        continue;
      }
      double t1 = (box.min[a] - ray.origin[a]) / ray.dir[a], t2 = (box.max[a] - ray.origin[a]) / ray.dir[a];
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > t_near) {
        t_near = t1;
        axis = a;
      }
      t_far = std::min(t_far, t2);
    }
    if (t_near > t_far || t_near < 1e-6 || t_near >= t_best) continue;
    t_best = t_near;
    const Eigen::Vector3d p = ray.origin + t_near * ray.dir;
    // Faces differ in brightness (as under a ceiling light), so even a
    // texture-less box shows its edges.
    const double shade = axis == 0 ? 1.0 : axis == 1 ? 0.85 : 1.15;
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    gray = shade * (box.textured ? texture(p[a1], p[a2], box.seed + 17 * static_cast<uint32_t>(axis), box.gray,
                                           box.texture_scale)
                                 : box.gray);
    hit = true;
  }
  return hit;
}

double trace(const SyntheticScene& scene, const Ray& ray) {
  double t = std::numeric_limits<double>::infinity(), gray = scene.background_gray;
  hit_boxes(scene, ray, t, gray);
  if (ray.dir.z() < 0) {
    const double t_floor = -ray.origin.z() / ray.dir.z();
    if (t_floor > 1e-6 && t_floor < t) {
      const Eigen::Vector3d p = ray.origin + t_floor * ray.dir;
      gray = scene.floor_textured ? texture(p.x(), p.y(), scene.floor_seed, scene.floor_gray) : scene.floor_gray;
      for (const MirrorPatch& m : scene.mirrors) {
        if (p.x() < m.x_min || p.x() > m.x_max || p.y() < m.y_min || p.y() > m.y_max) continue;
        Ray bounce{p, {ray.dir.x(), ray.dir.y(), -ray.dir.z()}};
        double t2 = std::numeric_limits<double>::infinity(), mirrored = scene.background_gray;
        hit_boxes(scene, bounce, t2, mirrored);
        gray = (1 - m.reflectance) * gray + m.reflectance * mirrored;
        break;
      }
    }
  }
  return gray;
}

cv::Mat render_view(const SyntheticScene& scene, const CameraIntrinsics& cam, const Eigen::Isometry3d& to_robot,
                    int supersample, uint32_t noise_seed) {
  for (double d : cam.D)
    if (d != 0) throw std::invalid_argument("render_pair needs an undistorted rig");
  const Eigen::Matrix3d K_inv = cam.K.inverse();
  cv::Mat gray(cam.height, cam.width, CV_32F);
  cv::parallel_for_(cv::Range(0, cam.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      float* out = gray.ptr<float>(v);
      for (int u = 0; u < cam.width; ++u) {
        double sum = 0;
        for (int sy = 0; sy < supersample; ++sy) {
          for (int sx = 0; sx < supersample; ++sx) {
            const double pu = u + (sx + 0.5) / supersample - 0.5, pv = v + (sy + 0.5) / supersample - 0.5;
            const Eigen::Vector3d dir = to_robot.linear() * (K_inv * Eigen::Vector3d(pu, pv, 1.0));
            sum += trace(scene, {to_robot.translation(), dir.normalized()});
          }
        }
        out[u] = static_cast<float>(sum / (supersample * supersample));
      }
    }
  });
  if (scene.noise_sigma > 0) {
    cv::Mat noise(gray.size(), CV_32F);
    cv::RNG rng(noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, scene.noise_sigma);
    gray += noise;
  }
  cv::Mat gray8, bgr;
  gray.convertTo(gray8, CV_8U);
  cv::merge(std::vector<cv::Mat>{gray8, gray8, gray8}, bgr);
  return bgr;
}

}  // namespace

void render_pair(const SyntheticScene& scene, const RigCalibration& rig, cv::Mat& left, cv::Mat& right,
                 int supersample) {
  Eigen::Isometry3d right_to_left = Eigen::Isometry3d::Identity();
  right_to_left.linear() = rig.stereo_R.transpose();
  right_to_left.translation() = -rig.stereo_R.transpose() * rig.stereo_T;
  left = render_view(scene, rig.left, rig.left_to_robot, supersample, 11);
  right = render_view(scene, rig.right, rig.left_to_robot * right_to_left, supersample, 12);
}

bool footprint_occupied(const SyntheticScene& scene, double x, double y, double radius) {
  for (const SceneBox& box : scene.boxes) {
    if (box.max.z() < 0.05) continue;
    const double dx = std::max({box.min.x() - x, 0.0, x - box.max.x()});
    const double dy = std::max({box.min.y() - y, 0.0, y - box.max.y()});
    if (dx * dx + dy * dy <= radius * radius) return true;
  }
  return false;
}

}  // namespace ivoa::test
