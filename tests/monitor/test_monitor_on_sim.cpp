// The depth monitor against the simulator's analytic ground truth, on
// frames along joystick-like trajectories in several scenes: where it gives
// a verdict it must agree with the scene geometry on >= 99% of cells, and it
// must leave cells it cannot see unlabelled.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/monitor/depth_monitor.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"

namespace ivoa::monitor {
namespace {

using G = obstacle_grid_t;

struct Tally {
  int agree = 0, disagree = 0, unknown = 0, unseen_labelled = 0, obstacles = 0, free = 0;
};

void run_scene(const std::string& scene_file, uint64_t seed, int frames, Tally& tally) {
  const sim::Scene scene = sim::generate_scene(sim::load_scene_spec(scene_file), seed);
  const sim::Simulator simulator(scene);
  sim::Trajectory trajectory(scene, seed);
  const RigGeometry geometry(simulator.rig());
  const QueryGrid grid(QueryGridConfig{}, geometry.left);
  const DepthMonitor monitor(simulator.rig());
  sim::TruthQuery query;
  query.radius = grid.config().safety_radius;
  query.min_height = monitor.config().obstacle_min_height;
  query.max_height = monitor.config().obstacle_max_height;
  for (int f = 0; f < frames; ++f) {
    const sim::Pose2D pose = trajectory.pose_at(4.0 * f + 1.0);
    const sim::SimFrame frame = simulator.render(pose, static_cast<uint64_t>(f));
    obstacle_grid_t out = make_obstacle_grid(grid, "depth_monitor", f);
    monitor.evaluate(frame.depth_mm, grid, out);
    for (int i = 0; i < grid.size(); ++i) {
      const QueryCell& c = grid.cell(i);
      const Eigen::Vector2d world(pose.x + std::cos(pose.yaw) * c.x - std::sin(pose.yaw) * c.y,
                                  pose.y + std::sin(pose.yaw) * c.x + std::cos(pose.yaw) * c.y);
      const bool truth_free = scene.truth_at(world, query) == sim::TruthState::kFree;
      const int8_t s = out.state[static_cast<size_t>(i)];
      const auto px = geometry.depth.project({c.x, c.y, 0.0});
      const bool seen_centre = px && geometry.depth.in_image(*px);
      if (s == G::STATE_UNKNOWN) {
        ++tally.unknown;
        continue;
      }
      // FREE needs the footprint's own ground seen (OBSTACLE may rest on
      // obstacle points inside a footprint whose centre is out of view).
      if (s == G::STATE_FREE && !seen_centre) ++tally.unseen_labelled;
      const bool agree = (s == G::STATE_FREE) == truth_free;
      agree ? ++tally.agree : ++tally.disagree;
      (s == G::STATE_FREE ? tally.free : tally.obstacles)++;
      if (!agree)
        std::printf("  disagree: %s seed %llu frame %d cell (%.2f, %.2f): monitor %s, truth %s, nearest solid %.3f m\n",
                    scene.name().c_str(), static_cast<unsigned long long>(seed), f, c.x, c.y,
                    s == G::STATE_FREE ? "FREE" : "OBSTACLE", truth_free ? "free" : "occupied", scene.clearance(world));
    }
  }
}

TEST(MonitorOnSimulator, AgreesWithSceneGeometryWhereItSpeaks) {
  Tally t;
  const std::string scenes = IVOA_SCENES_DIR;
  for (const char* name :
       {"indoor_office", "corridor", "polished_lobby", "warehouse", "outdoor_campus", "wet_parking_lot", "night_plaza"})
    run_scene(scenes + "/" + name + ".yaml", 11, 4, t);
  const int labelled = t.agree + t.disagree;
  const double agreement = static_cast<double>(t.agree) / labelled;
  std::printf("monitor vs truth: %d labelled cells (%d free, %d obstacle), %d unknown, agreement %.4f\n", labelled,
              t.free, t.obstacles, t.unknown, agreement);
  EXPECT_GE(agreement, 0.99);
  EXPECT_GT(t.obstacles, 20);  // the trajectories do meet obstacles
  EXPECT_GT(t.free, 200);
  EXPECT_GT(t.unknown, 100);  // and there is much it cannot see
  EXPECT_EQ(t.unseen_labelled, 0) << "cells whose ground is outside the depth image cannot be FREE";
}

}  // namespace
}  // namespace ivoa::monitor
