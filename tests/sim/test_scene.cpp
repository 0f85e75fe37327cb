// Analytic scene queries: footprint truth (obstacle / hole / free) and
// clearance, against elements placed exactly.
#include <gtest/gtest.h>

#include "ivoa/sim/elements.hpp"
#include "ivoa/sim/scene.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::sim {
namespace {

using namespace elements;

Scene exact_scene() {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(box({2.0, 0.0}, {0.4, 0.4, 0.5}));   // x in [1.8, 2.2], y in [-0.2, 0.2]
  spec.elements.push_back(box({2.0, 1.5}, {0.4, 0.4, 0.03}));  // a mat-like slab below min_height
  spec.elements.push_back(pit({2.0, -1.5}, {0.4, 0.4}, 0.3));  // x in [1.8, 2.2], y in [-1.7, -1.3]
  ElementSpec table;
  table.type = ElementSpec::Type::kTable;
  table.position = {4.0, 0.0};
  table.size = {1.2, 0.7, 0.73};
  spec.elements.push_back(table);
  return generate_scene(spec, 1);
}

TEST(SimScene, FootprintTruthIsExact) {
  const Scene scene = exact_scene();
  TruthQuery q;  // r = 0.10, min height 0.05
  EXPECT_EQ(scene.truth_at({2.0, 0.0}, q), TruthState::kObstacle);
  EXPECT_EQ(scene.truth_at({1.8 - 0.099, 0.0}, q), TruthState::kObstacle);  // within r of the face
  EXPECT_EQ(scene.truth_at({1.8 - 0.101, 0.0}, q), TruthState::kFree);
  // Corner: the disc touches the box only within r of the corner point.
  EXPECT_EQ(scene.truth_at({1.8 - 0.07, 0.2 + 0.07}, q), TruthState::kObstacle);  // 0.099 from the corner
  EXPECT_EQ(scene.truth_at({1.8 - 0.072, 0.2 + 0.072}, q), TruthState::kFree);    // 0.102 from it
  EXPECT_EQ(scene.truth_at({2.0, 1.5}, q), TruthState::kFree) << "3 cm slab is below min_height";
  q.min_height = 0.02;
  EXPECT_EQ(scene.truth_at({2.0, 1.5}, q), TruthState::kObstacle);
  q.min_height = 0.05;
  EXPECT_EQ(scene.truth_at({2.0, -1.5}, q), TruthState::kHole);
  EXPECT_EQ(scene.truth_at({2.0, -1.3 + 0.09}, q), TruthState::kHole);
  EXPECT_EQ(scene.truth_at({2.0, -1.3 + 0.11}, q), TruthState::kFree);
  // Under the table top: the overhang counts unless above max_height.
  EXPECT_EQ(scene.truth_at({4.0, 0.0}, q), TruthState::kObstacle);
  q.max_height = 0.6;
  EXPECT_EQ(scene.truth_at({4.0, 0.0}, q), TruthState::kFree);
}

TEST(SimScene, SimulatorTruthUsesRobotFrame) {
  const Simulator sim(exact_scene());
  // Robot at (2, 1) facing -y: the box at world (2, 0) is 1 m ahead.
  const Pose2D pose{2.0, 1.0, -M_PI / 2};
  EXPECT_EQ(sim.footprint_truth(pose, 1.0, 0.0, 0.1), TruthState::kObstacle);
  EXPECT_EQ(sim.footprint_truth(pose, 0.6, 0.0, 0.1), TruthState::kFree);
  EXPECT_EQ(sim.footprint_truth(pose, 2.5, 0.0, 0.1), TruthState::kHole);
}

TEST(SimScene, ClearanceAndFreeDistance) {
  const Scene scene = exact_scene();
  EXPECT_NEAR(scene.clearance({1.0, 0.0}), 0.8, 1e-6);
  EXPECT_NEAR(scene.clearance({2.0, 0.0}), -0.2, 1e-6);
  EXPECT_NEAR(scene.free_distance({0.0, 0.0}, 0.0, 0.3, 10.0), 1.5, 1e-4);  // disc edge meets the face at x = 1.8
  EXPECT_NEAR(scene.free_distance({2.0, -0.8}, -M_PI / 2, 0.1, 10.0), 0.4, 1e-4);  // pit edge at y = -1.3
}

TEST(SimScene, RaycastHitsWhatIsThere) {
  const Scene scene = exact_scene();
  const auto hit = scene.raycast({0, 0, 0.25}, {1, 0, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 1.8, 1e-5);
  EXPECT_EQ(hit->surface, sim_ground_truth_t::SURFACE_BOX);
  EXPECT_NEAR(hit->normal.x(), -1, 1e-6);
  const auto floor = scene.raycast({0, 0, 0.3}, {1, 0, -0.3});
  ASSERT_TRUE(floor);
  EXPECT_EQ(floor->surface, sim_ground_truth_t::SURFACE_FLOOR);
  EXPECT_NEAR(floor->point.x(), 1.0, 1e-6);
  const auto into_pit = scene.raycast({2.0, -1.0, 0.3}, {0, -0.5, -0.3});  // floor hit inside the pit opening
  ASSERT_TRUE(into_pit);
  EXPECT_EQ(into_pit->surface, sim_ground_truth_t::SURFACE_PIT);
  EXPECT_LT(into_pit->point.z(), -0.01);
}

}  // namespace
}  // namespace ivoa::sim
