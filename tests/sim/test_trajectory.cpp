// The joystick-like drive: collision-free, varied, often close to things,
// deterministic.
#include <cmath>

#include <gtest/gtest.h>

#include "ivoa/core/query_grid.hpp"
#include "ivoa/sim/scene.hpp"
#include "ivoa/sim/trajectory.hpp"

namespace ivoa::sim {
namespace {

Scene shipped(const std::string& name, uint64_t seed) {
  return generate_scene(load_scene_spec(std::string(IVOA_SIM_SCENES_DIR) + "/" + name + ".yaml"), seed);
}

struct DriveStats {
  double min_clearance = 1e9, max_speed = 0, max_yaw_rate = 0, distance = 0;
  int close_approaches = 0;  // separate times the footprint came within 0.55 m of something
  int frames = 0, frames_with_obstacle_ahead = 0;
  double heading_spread = 0;  // |mean of unit heading vectors|: 0 = all directions
};

DriveStats drive(const Scene& scene, uint64_t seed, double seconds) {
  Trajectory t(scene, seed);
  DriveStats s;
  const double r = t.config().robot_radius;
  bool close = false;
  Pose2D prev = t.pose_at(0);
  double hx = 0, hy = 0;
  for (double time = 0.1; time <= seconds; time += 0.1) {
    const Pose2D p = t.pose_at(time);
    const Twist2D tw = t.twist_at(time);
    const double c = scene.clearance({p.x, p.y}) - r;
    s.min_clearance = std::min(s.min_clearance, c);
    s.max_speed = std::max(s.max_speed, tw.v);
    s.max_yaw_rate = std::max(s.max_yaw_rate, std::abs(tw.omega));
    s.distance += std::hypot(p.x - prev.x, p.y - prev.y);
    if (c < 0.55 && !close) ++s.close_approaches;
    close = c < 0.7 ? (close || c < 0.55) : false;
    hx += std::cos(p.yaw);
    hy += std::sin(p.yaw);
    // Does the ground query area 0.5-3 m ahead (|y| <= 1.5) hold an obstacle?
    if (std::fmod(time, 1.0) < 0.1) {
      ++s.frames;
      bool any = false;
      for (double x = 0.5; x <= 3.0 && !any; x += 0.25)
        for (double y = -1.5; y <= 1.5 && !any; y += 0.25)
          any = scene.truth_at(robot_to_world(p, x, y)) == TruthState::kObstacle;
      s.frames_with_obstacle_ahead += any;
    }
    prev = p;
  }
  s.heading_spread = std::hypot(hx, hy) / (seconds / 0.1);
  return s;
}

TEST(SimTrajectory, CollisionFreeVariedAndOftenClose) {
  for (const char* name : {"indoor_office", "corridor", "outdoor_campus"}) {
    SCOPED_TRACE(name);
    const Scene scene = shipped(name, 2);
    const DriveStats s = drive(scene, 2, 180.0);
    EXPECT_GE(s.min_clearance, 0.2) << "the footprint keeps its distance (0.3-0.5 m, less only while braking)";
    EXPECT_GT(s.distance, 15.0);
    EXPECT_GE(s.max_speed, 0.35);
    EXPECT_LE(s.max_speed, 0.6 + 1e-9);
    EXPECT_GT(s.max_yaw_rate, 0.4);
    EXPECT_GE(s.close_approaches, 5);
    EXPECT_LT(s.heading_spread, 0.7) << "headings should vary";
    EXPECT_GT(s.frames_with_obstacle_ahead, 0.4 * s.frames) << "the query grid should often contain obstacles";
  }
}

TEST(SimTrajectory, Deterministic) {
  const Scene scene = shipped("polished_lobby", 4);
  Trajectory a(scene, 9), b(scene, 9), c(scene, 10);
  // Queried in different orders: the plan does not depend on how it is read.
  const Pose2D late = b.pose_at(40.0);
  for (double t = 0; t <= 40.0; t += 0.37) {
    const Pose2D pa = a.pose_at(t), pb = b.pose_at(t);
    EXPECT_EQ(pa.x, pb.x);
    EXPECT_EQ(pa.y, pb.y);
    EXPECT_EQ(pa.yaw, pb.yaw);
  }
  EXPECT_EQ(a.pose_at(40.0).x, late.x);
  const Pose2D pc = c.pose_at(40.0);
  EXPECT_TRUE(pc.x != late.x || pc.y != late.y);
}

TEST(SimTrajectory, HoldsAMinuteOfThePlanAndPlansAnEarlierTimeAgain) {
  const Scene scene = shipped("indoor_office", 2);
  Trajectory asked(scene, 5);
  // A long session held only its last minute (it held every 20 ms step
  // before: 7 MB an hour of a simulated session).
  const Pose2D late = asked.pose_at(600.0);
  const std::size_t minute = static_cast<std::size_t>(60.0 / asked.config().step);
  EXPECT_LE(asked.steps_held(), minute + 2);
  // Within that minute, and before it (planned again from the start): the
  // answers of a trajectory that plans up to that time only.
  for (double t : {590.0, 541.0, 3.3, 120.0, 600.0}) {
    SCOPED_TRACE(t);
    Trajectory fresh(scene, 5);
    const Pose2D want = fresh.pose_at(t);
    EXPECT_EQ(asked.pose_at(t).x, want.x);
    EXPECT_EQ(asked.pose_at(t).y, want.y);
    EXPECT_EQ(asked.pose_at(t).yaw, want.yaw);
    EXPECT_EQ(asked.twist_at(t).v, fresh.twist_at(t).v);
  }
  EXPECT_EQ(asked.pose_at(600.0).yaw, late.yaw);
  Trajectory whole(scene, 5);
  whole.pose_at(600.0);
  asked.pose_at(1.0);  // planned again from the start, up to 1 s
  EXPECT_EQ(asked.min_clearance(), whole.min_clearance()) << "over every step planned, not since the restart";
}

}  // namespace
}  // namespace ivoa::sim
