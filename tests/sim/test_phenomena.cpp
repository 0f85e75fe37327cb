// The phenomena that make stereo fail are physical: a mirror-like floor
// really shows the reflected scene (which stereo places below the ground)
// while the depth sensor sees flat ground, and a texture-less wall really
// gives a matcher nothing to match while the depth sensor sees the wall.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/rectification.hpp"
#include "ivoa/sim/elements.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "sim_test_util.hpp"

namespace ivoa::sim {
namespace {

using namespace elements;
using GT = sim_ground_truth_t;

// Fraction of the depth sensor's valid pixels inside `region` (robot-frame
// predicate) and how many of them lie within `tolerance` of the plane z = 0.
struct GroundCheck {
  int valid = 0, total = 0, on_ground = 0;
};
template <class Region>
GroundCheck depth_on_ground(const SimFrame& f, const RigCalibration& rig, Region region, double tolerance = 0.03) {
  const CameraModel depth(rig.depth, rig.depth_to_robot);
  GroundCheck g;
  for (int v = 0; v < f.depth_mm.rows; ++v)
    for (int u = 0; u < f.depth_mm.cols; ++u) {
      // Where would this pixel see the ground? (Pixels aimed at the region.)
      const Eigen::Vector3d ray = depth.ray(Eigen::Vector2d(u, v)), o = depth.origin();
      if (ray.z() >= 0) continue;
      const Eigen::Vector3d ground = o + ray * (-o.z() / ray.z());
      if (!region(ground.x(), ground.y())) continue;
      ++g.total;
      const uint16_t mm = f.depth_mm.at<uint16_t>(v, u);
      if (!mm) continue;
      ++g.valid;
      const Eigen::Vector3d p = depth.unproject(Eigen::Vector2d(u, v), mm * 1e-3);
      g.on_ground += std::abs(p.z()) <= tolerance;
    }
  return g;
}

struct StereoVsGround {
  int compared = 0, off_ground = 0, reflection_pixels = 0;
};
// SGBM disparities of floor pixels inside `region` compared with the ground plane.
template <class Region>
StereoVsGround stereo_vs_ground(const SimFrame& f, const RigCalibration& rig, Region region) {
  const StereoRectification rect(rig);
  const test::RectifiedPair pair = test::rectify_with_truth(f, rig, rect);
  const cv::Mat d = test::sgbm_disparity(pair.left, pair.right);
  StereoVsGround s;
  for (int y = 0; y < d.rows; y += 2)
    for (int x = 100; x < d.cols; x += 2) {
      if (pair.true_surface.at<uint8_t>(y, x) != GT::SURFACE_FLOOR) continue;
      const Eigen::Vector3d p = rect.unproject(Eigen::Vector2d(x, y), pair.true_disparity.at<float>(y, x));
      if (!region(p.x(), p.y())) continue;
      s.reflection_pixels += (pair.true_phenomena.at<uint8_t>(y, x) & GT::PHENOMENON_REFLECTION) != 0;
      const float measured = d.at<float>(y, x);
      if (!std::isfinite(measured)) continue;
      ++s.compared;
      s.off_ground += std::abs(measured - test::ground_disparity(rect, x, y)) > 2.0;
    }
  return s;
}

// A poster wall 4 m ahead is what the floor mirrors.
SceneSpec room_with_floor_patch(const std::string& patch_material) {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(wall({4.0, -4}, {4.0, 4}, "poster_wall"));
  if (patch_material == "puddle") spec.elements.push_back(puddle({1.7, 0.0}, {1.6, 1.6}));
  else if (!patch_material.empty()) spec.elements.push_back(floor_patch({1.7, 0.0}, {1.6, 1.8}, patch_material));
  return spec;
}

TEST(SimPhenomena, ReflectiveFloorMisleadsStereoNotTheDepthSensor) {
  auto centre = [](double x, double y) { return x > 1.2 && x < 2.2 && std::abs(y) < 0.45; };
  // Dry carpet: SGBM follows the ground.
  const Simulator dry(generate_scene(room_with_floor_patch(""), 1));
  const SimFrame df = dry.render(Pose2D{}, 0);
  const StereoVsGround ds = stereo_vs_ground(df, dry.rig(), centre);
  ASSERT_GT(ds.compared, 500);
  EXPECT_LT(ds.off_ground, 0.1 * ds.compared);
  EXPECT_EQ(ds.reflection_pixels, 0);
  for (const char* material : {"puddle", "polished_stone"}) {
    SCOPED_TRACE(material);
    const Simulator wet(generate_scene(room_with_floor_patch(material), 1));
    const SimFrame f = wet.render(Pose2D{}, 0);
    const StereoVsGround s = stereo_vs_ground(f, wet.rig(), centre);
    EXPECT_GT(s.reflection_pixels, 500) << "the truth marks the mirror image";
    EXPECT_GT(s.compared, 300);
    EXPECT_GT(s.off_ground, 0.5 * s.compared) << "stereo should see the reflection, not the ground";
    // The depth sensor sees the flat floor there (some dropouts allowed).
    const GroundCheck g = depth_on_ground(f, wet.rig(), centre);
    EXPECT_GT(g.valid, 0.5 * g.total);
    EXPECT_GT(g.on_ground, 0.95 * g.valid);
  }
}

// Sum of absolute differences over an 11x11 window for disparities 0..95:
// min / median tells how distinct the best match is (1 = flat, no match signal).
double match_contrast(const cv::Mat& l, const cv::Mat& r, int x, int y) {
  std::vector<double> costs;
  for (int d = 0; d < 96; ++d) {
    double c = 0;
    for (int j = -5; j <= 5; ++j)
      for (int i = -5; i <= 5; ++i) c += std::abs(l.at<uint8_t>(y + j, x + i) - r.at<uint8_t>(y + j, x + i - d));
    costs.push_back(c);
  }
  std::vector<double> sorted = costs;
  std::sort(sorted.begin(), sorted.end());
  return sorted.front() / std::max(1.0, sorted[sorted.size() / 2]);
}

TEST(SimPhenomena, TexturelessWallGivesNoMatchSignal) {
  auto median_contrast = [](const std::string& material, const GroundCheck* unused) {
    (void)unused;
    SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
    spec.elements.push_back(wall({1.2, -3}, {1.2, 3}, material));
    const Simulator sim(generate_scene(spec, 1));
    const SimFrame f = sim.render(Pose2D{}, 0);
    const StereoRectification rect(sim.rig());
    const test::RectifiedPair pair = test::rectify_with_truth(f, sim.rig(), rect);
    std::vector<double> contrast;
    int textureless = 0, wall_pixels = 0;
    for (int y = 40; y < 260; y += 20)
      for (int x = 200; x < 900; x += 35) {
        if (pair.true_surface.at<uint8_t>(y, x) != GT::SURFACE_WALL) continue;
        ++wall_pixels;
        textureless += (pair.true_phenomena.at<uint8_t>(y, x) & GT::PHENOMENON_TEXTURELESS) != 0;
        contrast.push_back(match_contrast(pair.left, pair.right, x, y));
      }
    EXPECT_GT(wall_pixels, 100);
    std::nth_element(contrast.begin(), contrast.begin() + contrast.size() / 2, contrast.end());
    // The depth sensor sees the wall where it is.
    const CameraModel depth(sim.rig().depth, sim.rig().depth_to_robot);
    int valid = 0, on_wall = 0, aimed = 0;
    for (int v = 20; v < 200; v += 4)
      for (int u = 20; u < 620; u += 4) {
        ++aimed;
        const uint16_t mm = f.depth_mm.at<uint16_t>(v, u);
        if (!mm) continue;
        ++valid;
        on_wall += std::abs(depth.unproject(Eigen::Vector2d(u, v), mm * 1e-3).x() - 1.14) < 0.03;
      }
    EXPECT_GT(valid, 0.9 * aimed) << material;
    EXPECT_GT(on_wall, 0.95 * valid) << material;
    return std::make_pair(contrast[contrast.size() / 2], textureless == wall_pixels);
  };
  const auto paint = median_contrast("paint_white", nullptr);
  const auto brick = median_contrast("brick_red", nullptr);
  EXPECT_TRUE(paint.second) << "paint is marked texture-less";
  EXPECT_FALSE(brick.second);
  EXPECT_GT(paint.first, 0.8) << "painted wall: the matching cost is flat across disparities";
  EXPECT_LT(brick.first, 0.5) << "brick wall: a clear best match";
}

TEST(SimPhenomena, TruthMarksPhenomenaWhereTheyAre) {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "tile_white");
  spec.elements.push_back(wall({7.0, -4}, {7.0, 4}, "paint_white", 2.5, 0.12, "baseboard_black"));
  spec.elements.push_back(ceiling_light({4.5, 0.0}, {0.6, 0.6}, 400));  // a glaring panel the tiles mirror
  const Simulator sim(generate_scene(spec, 1));
  const SimFrame f = sim.render(Pose2D{}, 0);
  int counts[8] = {};
  for (int y = 0; y < f.truth_phenomena.rows; ++y)
    for (int x = 0; x < f.truth_phenomena.cols; ++x) {
      const uint8_t p = f.truth_phenomena.at<uint8_t>(y, x), s = f.truth_surface.at<uint8_t>(y, x);
      for (int b = 0; b < 7; ++b) counts[b] += (p >> b) & 1;
      if (p & GT::PHENOMENON_DARK_STRIPE) {
        EXPECT_EQ(s, GT::SURFACE_BASEBOARD);
      }
      if (p & (GT::PHENOMENON_REPETITIVE | GT::PHENOMENON_GLARE | GT::PHENOMENON_REFLECTION)) {
        EXPECT_EQ(s, GT::SURFACE_FLOOR);
      }
    }
  EXPECT_GT(counts[1], 10000) << "texture-less wall";
  EXPECT_GT(counts[3], 500) << "dark baseboard";
  EXPECT_GT(counts[4], 100000) << "tiles";
  EXPECT_GT(counts[0], 1000) << "the tiles mirror the wall";
  EXPECT_GT(counts[2], 500) << "glare of the panel in the floor";
  EXPECT_GT(counts[6], 200) << "the glare saturates";
  EXPECT_LT(counts[5], 0.05 * f.truth_phenomena.total()) << "well lit";
  // Low light: a room without the glaring panel, dimmed to 0.3 %: exposure
  // and gain run out and noise dominates.
  SceneSpec dim_spec = make_bare_spec(Environment::kIndoor, "tile_white");
  dim_spec.elements.push_back(wall({7.0, -4}, {7.0, 4}, "paint_white"));
  dim_spec.lighting.low_light_factor = Range(0.003);
  dim_spec.phenomena.low_light = 1.0;
  const SimFrame dim = Simulator(generate_scene(dim_spec, 1)).render(Pose2D{}, 0);
  EXPECT_GT(cv::countNonZero(dim.truth_phenomena & GT::PHENOMENON_LOW_LIGHT), 0.5 * dim.truth_phenomena.total());
  EXPECT_DOUBLE_EQ(dim.gain, SimulatorConfig{}.camera.max_gain);
}

TEST(SimPhenomena, DepthNoiseGrowsWithRange) {
  auto wall_noise = [](double distance) {
    SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
    spec.elements.push_back(wall({distance, -5}, {distance, 5}, "paint_grey", 3.0));
    const Simulator sim(generate_scene(spec, 1));
    const SimFrame f = sim.render(Pose2D{}, 0);
    const CameraModel depth(sim.rig().depth, sim.rig().depth_to_robot);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int v = 40; v < 120; ++v)
      for (int u = 200; u < 440; ++u) {
        const uint16_t mm = f.depth_mm.at<uint16_t>(v, u);
        if (!mm) continue;
        const double x = depth.unproject(Eigen::Vector2d(u, v), mm * 1e-3).x() - (distance - 0.06);
        sum += x;
        sum2 += x * x;
        ++n;
      }
    EXPECT_GT(n, 5000);
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
  };
  const double near = wall_noise(1.0), far = wall_noise(3.5);
  EXPECT_NEAR(near, 1.4e-3 * 1.0, 0.0012);
  EXPECT_NEAR(far, 1.4e-3 * 3.5 * 3.5, 0.006);
}

}  // namespace
}  // namespace ivoa::sim
