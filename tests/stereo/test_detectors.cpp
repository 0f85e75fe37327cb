// The detectors on ray-cast scenes with exact ground truth: what they must
// see (a textured box, free textured floor) and the failures the IVOA paper
// reports for JPP-C where physics says they happen (a texture-less wall read
// as free, a reflective floor read as an obstacle).
#include <cmath>
#include <functional>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/rectification.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/jppc_detector.hpp"
#include "synthetic_scene.hpp"
#include "test_rig.hpp"

namespace ivoa::stereo {
namespace {

using test::SceneBox;
using test::SyntheticScene;

// A room: textured floor, a textured back wall 4 m ahead (with a horizon in
// view SGBM matches garbage in the distant, aliased floor).
SyntheticScene room() {
  SyntheticScene scene;
  scene.boxes.push_back({{4.0, -4.0, 0.0}, {4.2, 4.0, 2.5}, true, 140, 9, 3.0});
  return scene;
}

struct Verdicts {
  QueryGrid grid;
  obstacle_grid_t jppc, dense;
};

Verdicts run_detectors(const SyntheticScene& scene) {
  const RigCalibration rig = test::make_test_rig(15.0);
  cv::Mat left, right;
  test::render_pair(scene, rig, left, right);
  Verdicts out{QueryGrid(QueryGridConfig{}, CameraModel(rig.left, rig.left_to_robot)), {}, {}};
  for (auto [name, msg] : {std::pair<const char*, obstacle_grid_t*>{"jppc", &out.jppc}, {"dense", &out.dense}}) {
    auto detector = make_detector(name, rig, DetectorConfig{});
    detector->set_frame(left, right);
    *msg = make_obstacle_grid(out.grid, name, 1);
    detector->evaluate(out.grid, *msg);
  }
  return out;
}

struct Tally {
  int free = 0, obstacle = 0, unknown = 0;
  int observed() const { return free + obstacle; }
};

Tally tally(const Verdicts& v, const obstacle_grid_t& msg, const std::function<bool(const QueryCell&)>& select) {
  Tally t;
  for (int i = 0; i < v.grid.size(); ++i) {
    if (!select(v.grid.cell(i))) continue;
    const int8_t s = msg.state[static_cast<size_t>(i)];
    (s == obstacle_grid_t::STATE_FREE ? t.free : s == obstacle_grid_t::STATE_OBSTACLE ? t.obstacle : t.unknown)++;
  }
  return t;
}

auto all_cells = [](const QueryCell&) { return true; };

TEST(Detectors, TexturedFloorIsFree) {
  const Verdicts v = run_detectors(room());
  const Tally jppc = tally(v, v.jppc, all_cells), dense = tally(v, v.dense, all_cells);
  EXPECT_EQ(jppc.obstacle, 0);
  EXPECT_GT(jppc.free, 70);
  EXPECT_GE(dense.free, 0.95 * dense.observed());
  EXPECT_GT(dense.free, 70);
}

TEST(Detectors, CellsOutOfViewAreUnknown) {
  const Verdicts v = run_detectors(room());
  // Near and far to the side: the footprint is outside the left image.
  for (const auto* msg : {&v.jppc, &v.dense}) {
    const Tally t = tally(v, *msg, [](const QueryCell& c) { return c.x <= 0.75 && std::abs(c.y) >= 1.0; });
    EXPECT_GT(t.unknown, 0);
    EXPECT_EQ(t.observed(), 0) << msg->detector;
  }
}

TEST(Detectors, TexturedBoxIsDetected) {
  SyntheticScene scene = room();
  const SceneBox box{{1.4, -0.3, 0.0}, {1.7, 0.3, 0.4}, true, 150, 3};
  scene.boxes.push_back(box);
  const Verdicts v = run_detectors(scene);
  auto on_box = [&](const QueryCell& c) { return test::footprint_occupied(scene, c.x, c.y, 0.1); };
  const Tally jppc = tally(v, v.jppc, on_box);
  EXPECT_EQ(jppc.obstacle, 6);  // 2 rows x 3 columns of the grid touch the box
  EXPECT_EQ(jppc.free + jppc.unknown, 0);
  // The box's front face is in the nearest row of cells touching it.
  const Tally dense_front = tally(v, v.dense, [&](const QueryCell& c) { return on_box(c) && c.x < 1.6; });
  EXPECT_EQ(dense_front.obstacle, 3);
  EXPECT_EQ(tally(v, v.dense, on_box).free, 0);
  // The floor in front of the box stays free.
  auto in_front = [](const QueryCell& c) { return c.x <= 1.25 && std::abs(c.y) <= 0.5; };
  EXPECT_EQ(tally(v, v.jppc, in_front).obstacle, 0);
  EXPECT_EQ(tally(v, v.dense, in_front).obstacle, 0);
}

// A cabinet 1.2 m ahead, 2 m wide, 0.4 m deep: cells at x = 1.5 lie inside it.
SyntheticScene cabinet(bool textured) {
  SyntheticScene scene = room();
  scene.boxes.push_back({{1.2, -1.0, 0.0}, {1.6, 1.0, 0.8}, textured, 150, 5});
  return scene;
}

TEST(Detectors, JppcMissesTexturelessWallButSeesTexturedOne) {
  // The JPP-C false negative of the paper: ground points behind a
  // texture-less face project onto it; zero descriptors match at any
  // disparity, so the ground hypothesis is "confirmed" and the cell is free.
  auto inside = [](const QueryCell& c) { return std::abs(c.x - 1.5) < 1e-6 && std::abs(c.y) <= 0.75; };
  const Verdicts plain = run_detectors(cabinet(false));
  const Tally missed = tally(plain, plain.jppc, inside);
  EXPECT_EQ(missed.free, 7);
  const Verdicts textured = run_detectors(cabinet(true));
  EXPECT_EQ(tally(textured, textured.jppc, inside).obstacle, 7);
  // Dense stereo finds no disparity on the blank face: it does not claim free.
  EXPECT_EQ(tally(plain, plain.dense, inside).free, 0);
}

TEST(Detectors, JppcFlagsReflectiveFloorAsObstacle) {
  // The JPP-C false positive of the paper: a wet/polished patch mirrors the
  // textured back wall, which appears at a virtual depth below the floor;
  // the ground hypothesis no longer matches and free floor reads as obstacle.
  SyntheticScene scene = room();
  scene.mirrors.push_back({1.0, 2.2, -0.8, 0.8, 0.85});
  auto on_patch = [](const QueryCell& c) { return c.x >= 1.0 && c.x <= 2.0 && std::abs(c.y) <= 0.75; };
  const Verdicts mirror = run_detectors(scene);
  const Tally flagged = tally(mirror, mirror.jppc, on_patch);
  EXPECT_GE(flagged.obstacle, 0.75 * (flagged.observed() + flagged.unknown));
  EXPECT_GT(flagged.obstacle, 20);
  for (int i = 0; i < mirror.grid.size(); ++i)
    EXPECT_FALSE(test::footprint_occupied(scene, mirror.grid.cell(i).x, mirror.grid.cell(i).y, 0.1));
  // The same floor without the reflection is free.
  const Verdicts dry = run_detectors(room());
  EXPECT_EQ(tally(dry, dry.jppc, on_patch).obstacle, 0);
  // Dense stereo places the mirrored wall at its virtual position, below the
  // floor far beyond the patch: most of the patch loses its ground points and
  // is no longer confirmed free (where the faint floor texture still wins,
  // it is).
  EXPECT_LE(tally(mirror, mirror.dense, on_patch).free, 0.5 * tally(dry, dry.dense, on_patch).free);
}

TEST(Detectors, FactoryAndConfigErrors) {
  const RigCalibration rig = test::make_test_rig();
  EXPECT_EQ(make_detector("jppc", rig, {})->name(), "jppc");
  EXPECT_EQ(make_detector("dense", rig, {})->name(), "dense");
  EXPECT_THROW(make_detector("elas", rig, {}), std::invalid_argument);
  DetectorConfig config;
  config.jpp.grid_size = 50;  // JPP's .cfg is in mm
  EXPECT_THROW(make_detector("jppc", rig, config), std::invalid_argument);
  config = {};
  config.dense.sgbm.num_disparities = 100;
  EXPECT_THROW(make_detector("dense", rig, config), std::invalid_argument);
  // OpenCV aborted the process on a disparity range wider than the image.
  config = {};
  config.dense.sgbm.num_disparities = 496;
  try {
    make_detector("dense", rig, config);
    FAIL() << "a range wider than the 480 px rectified image was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("do not fit the rectified image, 480 px wide"), std::string::npos) << e.what();
  }
  config = {};
  config.jpp.grid_size = 1e-5;  // its sample count overflowed: every cell free
  EXPECT_THROW(make_detector("jppc", rig, config), std::invalid_argument);
  config = {};
  config.jpp.daisy_R = 1e6;  // hung on every frame
  EXPECT_THROW(make_detector("jppc", rig, config), std::invalid_argument);
}

TEST(Detectors, WrongImageSizeIsAFrameError) {
  const RigCalibration rig = test::make_test_rig();
  for (const char* name : {"jppc", "dense"}) {
    auto detector = make_detector(name, rig, {});
    const cv::Mat small(480, 640, CV_8UC3, cv::Scalar::all(0)), right(600, 960, CV_8UC3, cv::Scalar::all(0));
    EXPECT_THROW(detector->set_frame(small, right), FrameError) << name;
    EXPECT_THROW(detector->set_frame(right, cv::Mat(600, 960, CV_16UC1)), FrameError) << name;
    detector->set_frame(right, cv::Mat(600, 960, CV_8UC1, cv::Scalar(0)));  // gray and BGR may mix
  }
}

TEST(Detectors, EvaluateRejectsAGridOfAnotherSize) {
  const RigCalibration rig = test::make_test_rig();
  const QueryGrid grid(QueryGridConfig{}, CameraModel(rig.left, rig.left_to_robot));
  QueryGridConfig other;
  other.spacing = 0.5;
  obstacle_grid_t msg = make_obstacle_grid(QueryGrid(other, CameraModel(rig.left, rig.left_to_robot)), "jppc", 0);
  EXPECT_THROW(make_detector("jppc", rig, {})->evaluate(grid, msg), std::invalid_argument);
}

TEST(Detectors, JppcRectifiesAsCoreDoes) {
  // JPP-C remaps regions itself with fixed-point taps recovered from core's
  // rectification maps.
  const RigCalibration rig = test::make_test_rig(15.0, true);
  const StereoRectification core_rect(rig, 0.5);
  cv::Mat left, right, left_gray, right_gray, core_left, core_right;
  test::render_pair(room(), test::make_test_rig(15.0), left, right, 1);
  cv::cvtColor(left, left_gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(right, right_gray, cv::COLOR_BGR2GRAY);
  core_rect.rectify(left_gray, right_gray, core_left, core_right);
  JppcDetector detector(rig, JppConfig{});
  detector.set_frame(left, right);
  detector.prepare_whole_image();
  cv::Mat diff;
  cv::absdiff(detector.left_rectified(), core_left, diff);
  EXPECT_LE(cv::norm(diff, cv::NORM_INF), 1.0);  // fixed-point rounding
  EXPECT_LT(cv::mean(diff)[0], 0.1);
  cv::absdiff(detector.right_rectified(), core_right, diff);
  EXPECT_LE(cv::norm(diff, cv::NORM_INF), 1.0);
  detector.set_frame(left_gray, right_gray);  // gray input: the same
  detector.prepare_whole_image();
  EXPECT_LE(cv::norm(detector.left_rectified(), core_left, cv::NORM_INF), 1.0);
}

TEST(Detectors, GrayAndColourInputGiveTheSameVerdicts) {
  // The process may hand either (it decodes colour); offline tools too.
  SyntheticScene scene = room();
  scene.boxes.push_back({{1.4, -0.3, 0.0}, {1.7, 0.3, 0.4}, true, 150, 3});
  const RigCalibration rig = test::make_test_rig(15.0);
  cv::Mat left, right, left_gray, right_gray;
  test::render_pair(scene, rig, left, right, 1);
  cv::cvtColor(left, left_gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(right, right_gray, cv::COLOR_BGR2GRAY);
  const QueryGrid grid(QueryGridConfig{}, CameraModel(rig.left, rig.left_to_robot));
  for (const char* name : {"jppc", "dense"}) {
    auto detector = make_detector(name, rig, {});
    obstacle_grid_t colour = make_obstacle_grid(grid, name, 0), gray = colour;
    detector->set_frame(left, right);
    detector->evaluate(grid, colour);
    detector->set_frame(left_gray, right_gray);
    detector->evaluate(grid, gray);
    EXPECT_EQ(colour.state, gray.state) << name;
  }
}

TEST(Detectors, JppcHalfBoxHasFifteenSamplesAndIsCachedPerPair) {
  // r = 0.10 m at JPP's 0.05 m step: dx in {0, .05, .10} x dy in 5 steps.
  const RigCalibration rig = test::make_test_rig();
  cv::Mat left, right;
  test::render_pair(room(), rig, left, right, 1);
  JppcDetector detector(rig, JppConfig{});
  detector.set_frame(left, right);
  EXPECT_EQ(detector.check(1.5, 0.0, 0.10), Verdict::kFree);
  EXPECT_EQ(detector.stats().cp_tests, 15);
  EXPECT_EQ(detector.check(1.5, 0.0, 0.10), Verdict::kFree);
  EXPECT_EQ(detector.stats().cp_cache_hits, 15);
  EXPECT_EQ(detector.check(-1.0, 0.0, 0.10), Verdict::kUnknown);  // behind the camera
}

TEST(Detectors, JppcDiscFootprintHasThirteenSamplesWithinR) {
  const RigCalibration rig = test::make_test_rig();
  cv::Mat left, right;
  test::render_pair(room(), rig, left, right, 1);
  JppConfig config;
  config.footprint = "disc";
  JppcDetector detector(rig, config);
  detector.set_frame(left, right);
  EXPECT_EQ(detector.check(1.5, 0.0, 0.10), Verdict::kFree);
  EXPECT_EQ(detector.stats().cp_tests, 13);  // the 0.05 m lattice points within 0.10 m
}

TEST(Detectors, JppcEvidenceIsTheWindowCostOfEverySample) {
  const RigCalibration rig = test::make_test_rig();
  cv::Mat left, right;
  test::render_pair(cabinet(true), rig, left, right, 1);
  const JppConfig config;
  JppcDetector detector(rig, config);
  detector.set_frame(left, right);
  for (const auto& [x, expected] : {std::pair{1.0, Verdict::kFree}, {1.5, Verdict::kObstacle}}) {
    const Evidence e = detector.evidence(x, 0.0, 0.10);
    EXPECT_EQ(e.verdict, expected) << x;
    EXPECT_EQ(e.verdict, detector.check(x, 0.0, 0.10)) << x;
    ASSERT_EQ(e.values.size(), 15u) << x;  // all samples, also after one fails
    int failing = 0;
    for (float cost : e.values) {
      ASSERT_TRUE(std::isfinite(cost));
      EXPECT_GE(cost, 0.0f);
      failing += cost >= config.conf_pos_thresh;
    }
    EXPECT_EQ(failing > 0, expected == Verdict::kObstacle) << x;
    if (expected == Verdict::kObstacle) {
      EXPECT_GT(failing, 1) << "the ground hidden by the face fails throughout";
    }
  }
  // Nothing seen: NaN for every sample, and the verdict check() gives.
  const Evidence behind = detector.evidence(-1.0, 0.0, 0.10);
  EXPECT_EQ(behind.verdict, Verdict::kUnknown);
  ASSERT_EQ(behind.values.size(), 15u);
  for (float cost : behind.values) EXPECT_TRUE(std::isnan(cost));
}

TEST(Detectors, DenseDetectorKeepsNoEvidence) {
  const RigCalibration rig = test::make_test_rig();
  cv::Mat left, right;
  test::render_pair(room(), rig, left, right, 1);
  auto detector = make_detector("dense", rig, {});
  detector->set_frame(left, right);
  const Evidence e = detector->evidence(1.5, 0.0, 0.10);
  EXPECT_TRUE(e.values.empty());
  EXPECT_EQ(e.verdict, detector->check(1.5, 0.0, 0.10));
}

}  // namespace
}  // namespace ivoa::stereo
