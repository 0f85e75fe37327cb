#pragma once
// A tiny ray caster for stereo tests with exact ground truth: a floor
// (z = 0), axis-aligned boxes and mirror patches on the floor, each textured
// with world-anchored value noise or flat grey, rendered into both cameras of
// an undistorted rig. Far simpler than libs/sim, and independent of it, so
// the detectors' physics can be tested in isolation: what a texture-less face
// or a reflection does to the matching cost.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/calibration.hpp"

namespace ivoa::test {

struct SceneBox {
  Eigen::Vector3d min, max;  // robot frame, metres
  bool textured = true;
  double gray = 150;  // mean (textured) or flat grey level
  uint32_t seed = 7;
  double texture_scale = 1;  // blob sizes 1.2, 3.5 and 10 cm times this
};

// A floor rectangle that reflects like a wet or polished floor: the pixel is
// (1 - reflectance) * floor + reflectance * what the mirrored ray sees.
struct MirrorPatch {
  double x_min, x_max, y_min, y_max;
  double reflectance = 0.85;
};

struct SyntheticScene {
  bool floor_textured = true;
  double floor_gray = 110;
  uint32_t floor_seed = 1;
  std::vector<SceneBox> boxes;
  std::vector<MirrorPatch> mirrors;
  double background_gray = 90;  // what rays that hit nothing see
  double noise_sigma = 0;       // Gaussian sensor noise, grey levels
};

// Renders the raw left and right images (8-bit BGR, the rig's sizes). The
// rig must be undistorted. `supersample` rays per pixel side (anti-aliasing).
void render_pair(const SyntheticScene& scene, const RigCalibration& rig, cv::Mat& left, cv::Mat& right,
                 int supersample = 2);

// Ground truth: does a box reach within `radius` (horizontal disc) of (x, y)?
bool footprint_occupied(const SyntheticScene& scene, double x, double y, double radius);

}  // namespace ivoa::test
