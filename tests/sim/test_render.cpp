// Rendering: deterministic, geometrically exact (core's camera models
// predict where things appear), and good enough for a standard stereo
// matcher on well-textured surfaces.
#include <cmath>

#include <gtest/gtest.h>

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

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

SceneSpec textured_room() {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(wall({3.2, -4}, {3.2, 4}, "brick_red"));
  spec.elements.push_back(box({2.0, 0.3}, {0.4, 0.4, 0.5}, "printed_box"));
  spec.elements.push_back(box({1.4, -0.7}, {0.3, 0.5, 0.35}, "cardboard", 0.4));
  return spec;
}

TEST(SimRender, OutputsHaveTheRigShapes) {
  const Simulator sim(generate_scene(textured_room(), 1));
  const SimFrame f = sim.render(Pose2D{}, 0);
  EXPECT_EQ(f.left.size(), cv::Size(960, 600));
  EXPECT_EQ(f.left.type(), CV_8UC3);
  EXPECT_EQ(f.right.size(), cv::Size(960, 600));
  EXPECT_EQ(f.depth_mm.size(), cv::Size(640, 480));
  EXPECT_EQ(f.depth_mm.type(), CV_16UC1);
  EXPECT_EQ(f.truth_depth.type(), CV_32FC1);
  EXPECT_EQ(f.truth_surface.type(), CV_8UC1);
  EXPECT_EQ(f.truth_phenomena.size(), cv::Size(960, 600));
  // The rig: baseline, height and pitch as specified, distortion present.
  const RigCalibration& rig = sim.rig();
  EXPECT_NEAR(rig.baseline(), 0.12, 0.005);
  EXPECT_NEAR(rig.left_to_robot.translation().z(), 0.30, 1e-9);
  const Eigen::Vector3d axis = rig.left_to_robot.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(std::asin(-axis.z()) * 180 / M_PI, 15.0, 0.01);
  EXPECT_NE(rig.left.D[0], 0.0);
  // The depth sensor respects its range.
  double lo = 1e9, hi = 0;
  for (auto it = f.depth_mm.begin<uint16_t>(); it != f.depth_mm.end<uint16_t>(); ++it)
    if (*it) lo = std::min<double>(lo, *it), hi = std::max<double>(hi, *it);
  EXPECT_GE(lo, 500 - 10);
  EXPECT_LE(hi, 4500 + 60);
}

TEST(SimRender, DeterministicAndAccelerationExact) {
  const Scene scene = generate_scene(load_scene_spec(std::string(IVOA_SIM_SCENES_DIR) + "/indoor_office.yaml"), 5);
  const Simulator sim(scene);
  const Pose2D pose = scene.start_pose();
  const SimFrame a = sim.render(pose, 17), b = sim.render(pose, 17);
  EXPECT_TRUE(identical(a.left, b.left));
  EXPECT_TRUE(identical(a.right, b.right));
  EXPECT_TRUE(identical(a.depth_mm, b.depth_mm));
  EXPECT_TRUE(identical(a.truth_depth, b.truth_depth));
  EXPECT_TRUE(identical(a.truth_surface, b.truth_surface));
  EXPECT_TRUE(identical(a.truth_phenomena, b.truth_phenomena));
  // Another frame index: fresh sensor noise, same scene.
  const SimFrame c = sim.render(pose, 18);
  EXPECT_FALSE(identical(a.left, c.left));
  EXPECT_TRUE(identical(a.truth_surface, c.truth_surface));
  // The brute-force baseline (every solid for every pixel) renders the same images.
  SimulatorConfig brute;
  brute.use_acceleration = false;
  const SimFrame d = Simulator(scene, brute).render(pose, 17);
  EXPECT_TRUE(identical(a.left, d.left));
  EXPECT_TRUE(identical(a.right, d.right));
  EXPECT_TRUE(identical(a.depth_mm, d.depth_mm));
  EXPECT_TRUE(identical(a.truth_depth, d.truth_depth));
}

// The top left corner of a box's front face, where core's camera models put it.
TEST(SimRender, NoiseSeedDrawsOtherNoiseForTheSameFrame) {
  const Scene scene = generate_scene(load_scene_spec(std::string(IVOA_SIM_SCENES_DIR) + "/indoor_office.yaml"), 5);
  SimulatorConfig other_noise;
  other_noise.noise_seed = 3;
  const Simulator sim(scene), resampled(scene, other_noise);
  const Pose2D pose = scene.start_pose();
  const SimFrame a = sim.render(pose, 17), b = resampled.render(pose, 17);
  EXPECT_FALSE(identical(a.left, b.left));
  EXPECT_FALSE(identical(a.right, b.right));
  EXPECT_FALSE(identical(a.depth_mm, b.depth_mm));
  EXPECT_TRUE(identical(a.truth_depth, b.truth_depth));
  EXPECT_TRUE(identical(a.truth_surface, b.truth_surface));
  EXPECT_EQ(a.exposure_ms, b.exposure_ms);
  // Only the noise differs: the images agree to within a few gray levels on average.
  EXPECT_LT(cv::norm(a.left, b.left, cv::NORM_L1) / static_cast<double>(a.left.total() * 3), 8.0);
  EXPECT_TRUE(identical(b.left, resampled.render(pose, 17).left));  // and the realisation is reproducible
}

TEST(SimRender, MaterialJitterChangesHowThingsLookNotWhereTheyAre) {
  SceneSpec spec = load_scene_spec(std::string(IVOA_SIM_SCENES_DIR) + "/indoor_office.yaml");
  const Scene plain = generate_scene(spec, 5);
  spec.material_jitter = 1.0;  // the most it draws
  const Scene jittered = generate_scene(spec, 5);
  const Pose2D pose = plain.start_pose();
  EXPECT_EQ(jittered.start_pose().x, pose.x);
  const SimFrame a = Simulator(plain).render(pose, 17), b = Simulator(jittered).render(pose, 17);
  EXPECT_TRUE(identical(a.truth_depth, b.truth_depth));
  EXPECT_TRUE(identical(a.truth_surface, b.truth_surface));
  // How bright a surface is decides whether a mirror image outshines it
  // and where the image is under- or over-exposed; texture, periodicity,
  // glare and dark stripes are the materials' and the lights'.
  const auto of_the_scene = cv::Scalar(
      static_cast<uint8_t>(~(GT::PHENOMENON_REFLECTION | GT::PHENOMENON_LOW_LIGHT | GT::PHENOMENON_SATURATED)));
  cv::Mat a_phenomena, b_phenomena;
  cv::bitwise_and(a.truth_phenomena, of_the_scene, a_phenomena);
  cv::bitwise_and(b.truth_phenomena, of_the_scene, b_phenomena);
  EXPECT_TRUE(identical(a_phenomena, b_phenomena));
  // Far more than another noise draw's few gray levels (the test above).
  EXPECT_GT(cv::norm(a.left, b.left, cv::NORM_L1) / static_cast<double>(a.left.total() * 3), 12.0);
  EXPECT_TRUE(identical(b.left, Simulator(generate_scene(spec, 5)).render(pose, 17).left));
}

TEST(SimRender, MaterialJitterKeepsADarkBaseboardDark) {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(wall({2.0, -4}, {2.0, 4}, "paint_white", 2.5, 0.12, "baseboard_brown"));
  spec.material_jitter = 1.0;
  // Seeds that drew it lighter: 49 drew a mean luminance of 0.022 before
  // dark materials only darkened, 4 one of 0.018.
  for (const uint64_t seed : {4, 49, 160}) {
    SCOPED_TRACE(seed);
    const SimFrame f = Simulator(generate_scene(spec, seed)).render(Pose2D{}, 0);
    cv::Mat stripe;
    cv::bitwise_and(f.truth_phenomena, cv::Scalar(GT::PHENOMENON_DARK_STRIPE), stripe);
    EXPECT_GT(cv::countNonZero(stripe), 1000);
  }
}

TEST(SimRender, BoxCornerAppearsWhereTheCalibrationPredicts) {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(box({2.0, 0.3}, {0.4, 0.4, 0.5}, "plastic_red"));
  const Simulator sim(generate_scene(spec, 1));
  const SimFrame f = sim.render(Pose2D{}, 0);
  const RigGeometry geometry(sim.rig());
  const Eigen::Vector3d corner(1.8, 0.5, 0.5);  // front face x = 1.8, left side y = 0.5, top z = 0.5
  // Left: the truth image switches to BOX exactly there.
  const auto pl = geometry.left.project(corner);
  ASSERT_TRUE(pl && geometry.left.in_image(*pl, 10));
  const int ul = static_cast<int>(std::lround(pl->x())), vl = static_cast<int>(std::lround(pl->y()));
  EXPECT_EQ(f.truth_surface.at<uint8_t>(vl + 2, ul + 2), GT::SURFACE_BOX);
  EXPECT_NE(f.truth_surface.at<uint8_t>(vl - 2, ul + 2), GT::SURFACE_BOX);
  EXPECT_NE(f.truth_surface.at<uint8_t>(vl + 2, ul - 2), GT::SURFACE_BOX);
  const double planar = geometry.left.to_camera(corner).z();
  EXPECT_NEAR(f.truth_depth.at<float>(vl + 1, ul + 1), planar, 0.01);
  // Right: the red box shows up there (colour, through noise and demosaicing).
  const auto pr = geometry.right.project(corner);
  ASSERT_TRUE(pr && geometry.right.in_image(*pr, 10));
  auto red = [&](int u, int v) {
    const cv::Vec3b c = f.right.at<cv::Vec3b>(v, u);
    return c[2] > 2 * c[1] + 10 && c[2] > 2 * c[0] + 10;
  };
  const int ur = static_cast<int>(std::lround(pr->x())), vr = static_cast<int>(std::lround(pr->y()));
  EXPECT_TRUE(red(ur + 3, vr + 3));
  EXPECT_FALSE(red(ur + 3, vr - 3));
  EXPECT_FALSE(red(ur - 3, vr + 3));
  EXPECT_FALSE(red(ur - 3, vr - 3));
  // Depth: the face's range just inside the corner, not just outside it.
  const auto pd = geometry.depth.project(corner);
  ASSERT_TRUE(pd && geometry.depth.in_image(*pd, 10));
  const int ud = static_cast<int>(std::lround(pd->x())), vd = static_cast<int>(std::lround(pd->y()));
  const double expected_mm = geometry.depth.to_camera(corner).z() * 1000;
  std::vector<uint16_t> inside;  // a 3x3 block: an isolated dropout must not decide the test
  for (int dv = 2; dv <= 4; ++dv)
    for (int du = 2; du <= 4; ++du)
      if (const uint16_t z = f.depth_mm.at<uint16_t>(vd + dv, ud + du)) inside.push_back(z);
  ASSERT_GE(inside.size(), 5u);
  std::nth_element(inside.begin(), inside.begin() + inside.size() / 2, inside.end());
  EXPECT_NEAR(inside[inside.size() / 2], expected_mm, 25);
  const uint16_t outside = f.depth_mm.at<uint16_t>(vd - 3, ud - 3);
  EXPECT_TRUE(outside == 0 || outside > expected_mm + 500);
}

// Every floor pixel's true depth lies on the ground plane.
TEST(SimRender, TruthDepthOfTheFloorIsThePlane) {
  const Simulator sim(generate_scene(textured_room(), 1));
  const Pose2D pose{0.2, -0.1, 0.1};
  const SimFrame f = sim.render(pose, 0);
  const CameraModel left(sim.rig().left, sim.rig().left_to_robot);
  int floor = 0;
  double worst = 0;
  for (int v = 0; v < f.truth_depth.rows; v += 7)
    for (int u = 0; u < f.truth_depth.cols; u += 7) {
      if (f.truth_surface.at<uint8_t>(v, u) != GT::SURFACE_FLOOR) continue;
      const Eigen::Vector3d p = left.unproject(Eigen::Vector2d(u, v), f.truth_depth.at<float>(v, u));
      worst = std::max(worst, std::abs(p.z()));
      ++floor;
    }
  EXPECT_GT(floor, 3000);
  EXPECT_LT(worst, 1e-4);
}

// OpenCV's SGBM on the rectified pair agrees with the true disparity.
TEST(SimRender, SgbmMatchesTrueDisparityOnTexturedScene) {
  const Simulator sim(generate_scene(textured_room(), 1));
  const SimFrame f = sim.render(Pose2D{}, 3);
  const StereoRectification rect(sim.rig());
  const test::RectifiedPair pair = test::rectify_with_truth(f, sim.rig(), rect);
  const cv::Mat d = test::sgbm_disparity(pair.left, pair.right, 128);
  int compared = 0, good = 0, truth_pixels = 0;
  // Within SGBM's search range (the nearest floor is beyond it), away from
  // the left border it cannot match.
  for (int y = 0; y < d.rows; ++y)
    for (int x = 140; x < d.cols; ++x) {
      const float t = pair.true_disparity.at<float>(y, x);
      if (!std::isfinite(t) || t > 120) continue;
      ++truth_pixels;
      const float s = d.at<float>(y, x);
      if (!std::isfinite(s)) continue;
      ++compared;
      good += std::abs(s - t) <= 1.0f;
    }
  EXPECT_GT(compared, 0.6 * truth_pixels) << "SGBM found too few matches";
  EXPECT_GE(good, 0.9 * compared) << good << " of " << compared << " within 1 px";
}

}  // namespace
}  // namespace ivoa::sim
