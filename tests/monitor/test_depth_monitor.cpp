#include <gtest/gtest.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/monitor/depth_monitor.hpp"
#include "synthetic_depth.hpp"
#include "test_rig.hpp"

namespace ivoa::monitor {
namespace {

using G = obstacle_grid_t;

struct Fixture {
  RigCalibration rig = test::make_test_rig();
  RigGeometry geo{rig};
  QueryGrid grid{QueryGridConfig{}, geo.left};
  DepthMonitor monitor{rig};

  obstacle_grid_t run(const test::DepthScene& scene) const {
    obstacle_grid_t out = make_obstacle_grid(grid, "depth_monitor", 0);
    monitor.evaluate(test::render_depth(rig, scene), grid, out);
    return out;
  }
  // Does the depth sensor see the whole footprint disc of cell i?
  bool disc_visible(int i) const {
    const QueryCell& c = grid.cell(i);
    for (int k = 0; k < 16; ++k) {
      const double a = k * M_PI / 8;
      const double x = c.x + 0.1 * std::cos(a), y = c.y + 0.1 * std::sin(a);
      const auto px = geo.depth.project({x, y, 0.0});
      if (!px || !geo.depth.in_image(*px)) return false;
      if (geo.depth.to_camera({x, y, 0.0}).z() > rig.depth_max_range) return false;
    }
    return true;
  }
};

TEST(DepthMonitor, FlatGroundIsFreeWhereSeenAndUnknownWhereNot) {
  const Fixture f;
  const obstacle_grid_t out = f.run({});
  int free = 0, unseen_unknown = 0;
  for (int i = 0; i < f.grid.size(); ++i) {
    EXPECT_NE(out.state[i], G::STATE_OBSTACLE) << "cell " << i;
    if (f.disc_visible(i)) {
      EXPECT_EQ(out.state[i], G::STATE_FREE)
          << "visible cell " << i << " at " << f.grid.cell(i).x << "," << f.grid.cell(i).y;
      ++free;
    }
    const auto px = f.geo.depth.project({f.grid.cell(i).x, f.grid.cell(i).y, 0});
    if (!px || !f.geo.depth.in_image(*px)) {
      EXPECT_EQ(out.state[i], G::STATE_UNKNOWN) << "cell outside the depth view " << i;
      ++unseen_unknown;
    }
  }
  EXPECT_GT(free, 40);
  EXPECT_GT(unseen_unknown, 10);  // near the robot the depth view is narrow
}

TEST(DepthMonitor, AgreesWithGeometryAroundABoxAndDoesNotGuessBehindIt) {
  const Fixture f;
  test::DepthScene scene;
  scene.boxes.push_back({1.55, 1.9, -0.3, 0.2, 0.4});  // front face 5 cm beyond the x = 1.5 row
  const obstacle_grid_t out = f.run(scene);
  int obstacles = 0, checked = 0;
  for (int i = 0; i < f.grid.size(); ++i) {
    const QueryCell& c = f.grid.cell(i);
    const double d = test::distance_to_nearest_obstacle(scene, c.x, c.y);
    if (out.state[i] == G::STATE_UNKNOWN || std::abs(d - 0.1) < 0.02) continue;  // sensor-noise band at r
    ++checked;
    EXPECT_EQ(out.state[i], d <= 0.1 ? G::STATE_OBSTACLE : G::STATE_FREE) << c.x << "," << c.y << " d=" << d;
    obstacles += out.state[i] == G::STATE_OBSTACLE;
  }
  EXPECT_GE(obstacles, 3);
  EXPECT_GT(checked, 30);
  // Directly behind the box the ground is hidden: no verdict.
  EXPECT_EQ(out.state[f.grid.index(8, 6)], G::STATE_UNKNOWN);   // x = 2.5, y = 0
  EXPECT_EQ(out.state[f.grid.index(10, 6)], G::STATE_UNKNOWN);  // x = 3.0, y = 0
}

TEST(DepthMonitor, ObstaclesLowerThanTheThresholdAreNeverObstacles) {
  const Fixture f;
  test::DepthScene scene;
  scene.boxes.push_back({1.45, 1.55, -0.05, 0.05, 0.02});  // a 2 cm mat
  scene.boxes.push_back({2.4, 2.6, 0.4, 0.6, 0.03});       // a 3 cm threshold strip
  const obstacle_grid_t out = f.run(scene);
  // The mat hides a little ground behind it, so the cell may be UNKNOWN, but
  // what can be seen of it is below the obstacle height.
  EXPECT_NE(out.state[f.grid.index(4, 6)], G::STATE_OBSTACLE);  // x = 1.5, y = 0
  EXPECT_NE(out.state[f.grid.index(8, 8)], G::STATE_OBSTACLE);  // x = 2.5, y = 0.5
  EXPECT_EQ(out.state[f.grid.index(2, 6)], G::STATE_FREE);      // x = 1.0, y = 0: clear floor
}

TEST(DepthMonitor, PitIsANegativeObstacle) {
  const Fixture f;
  test::DepthScene scene;
  scene.pits.push_back({1.4, 1.85, -0.3, 0.3, 0.4});
  const obstacle_grid_t out = f.run(scene);
  EXPECT_EQ(out.state[f.grid.index(4, 6)], G::STATE_OBSTACLE);  // x = 1.5, y = 0: over the pit
  EXPECT_EQ(out.state[f.grid.index(2, 6)], G::STATE_FREE);      // x = 1.0, y = 0: before it
}

TEST(DepthMonitor, ZeroFilledDepthGivesNoVerdicts) {
  const Fixture f;
  obstacle_grid_t out = make_obstacle_grid(f.grid, "depth_monitor", 0);
  f.monitor.evaluate(cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)), f.grid, out);
  for (int8_t s : out.state) EXPECT_EQ(s, G::STATE_UNKNOWN);
}

TEST(DepthMonitor, WrongImageSizeIsRejectedWithSizes) {
  const Fixture f;
  obstacle_grid_t out = make_obstacle_grid(f.grid, "depth_monitor", 0);
  try {
    f.monitor.evaluate(cv::Mat(240, 320, CV_16UC1, cv::Scalar(1000)), f.grid, out);
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("320x240"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("640x480"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ivoa::monitor
