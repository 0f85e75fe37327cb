// The stereo detectors on simulator frames (libs/sim) with the simulator's
// footprint ground truth: what they must see, and the JPP-C failures the
// IVOA paper reports, where the rendered physics produces them.
#include <functional>

#include <gtest/gtest.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/stereo/detector.hpp"

namespace ivoa::stereo {
namespace {

using sim::ElementSpec;

ElementSpec wall(Eigen::Vector2d from, Eigen::Vector2d to, const std::string& material) {
  ElementSpec e;
  e.type = ElementSpec::Type::kWall;
  e.position = from;
  e.end = to;
  e.size = {0, 0.12, 2.5};
  e.material = material;
  return e;
}

ElementSpec box(Eigen::Vector2d centre, Eigen::Vector3d size, const std::string& material) {
  ElementSpec e;
  e.type = ElementSpec::Type::kBox;
  e.position = centre;
  e.size = size;
  e.material = material;
  return e;
}

ElementSpec floor_patch(ElementSpec::Type type, Eigen::Vector2d centre, Eigen::Vector2d size,
                        const std::string& material = "") {
  ElementSpec e;
  e.type = type;
  e.position = centre;
  e.size = {size.x(), size.y(), 0};
  e.material = material;
  return e;
}

// A bare floor with a printed poster wall 4 m ahead (so no horizon is in view).
sim::SceneSpec room(const std::string& floor = "carpet_grey") {
  sim::SceneSpec spec = sim::make_bare_spec(sim::Environment::kIndoor, floor);
  spec.elements.push_back(wall({4.0, -4.0}, {4.0, 4.0}, "poster_wall"));
  return spec;
}

struct Cell {
  QueryCell cell;
  int8_t jppc, dense;
  sim::TruthState truth;
};

// Renders the scene from the origin and runs both detectors on the default grid.
std::vector<Cell> run_detectors(const sim::SceneSpec& spec) {
  const sim::Simulator simulator(sim::generate_scene(spec, 1));
  const sim::Pose2D pose{0, 0, 0};
  const sim::SimFrame frame = simulator.render(pose, 0);
  const RigCalibration& rig = simulator.rig();
  const QueryGrid grid(QueryGridConfig{}, CameraModel(rig.left, rig.left_to_robot));
  obstacle_grid_t jppc = make_obstacle_grid(grid, "jppc", 0), dense = make_obstacle_grid(grid, "dense", 0);
  for (auto [name, msg] : {std::pair<const char*, obstacle_grid_t*>{"jppc", &jppc}, {"dense", &dense}}) {
    auto detector = make_detector(name, rig, DetectorConfig{});
    detector->set_frame(frame.left, frame.right);
    detector->evaluate(grid, *msg);
  }
  std::vector<Cell> cells;
  for (int i = 0; i < grid.size(); ++i) {
    const QueryCell& c = grid.cell(i);
    cells.push_back({c, jppc.state[static_cast<size_t>(i)], dense.state[static_cast<size_t>(i)],
                     simulator.footprint_truth(pose, c.x, c.y, grid.config().safety_radius)});
  }
  return cells;
}

struct Tally {
  int free = 0, obstacle = 0, unknown = 0;
  int observed() const { return free + obstacle; }
};

Tally tally(const std::vector<Cell>& cells, int8_t Cell::*detector, const std::function<bool(const Cell&)>& select) {
  Tally t;
  for (const Cell& c : cells) {
    if (!select(c)) continue;
    const int8_t s = c.*detector;
    (s == obstacle_grid_t::STATE_FREE ? t.free : s == obstacle_grid_t::STATE_OBSTACLE ? t.obstacle : t.unknown)++;
  }
  return t;
}

bool occupied(const Cell& c) { return c.truth == sim::TruthState::kObstacle; }

TEST(StereoOnSimulator, TexturedFreeFloorIsFree) {
  // Carpet: textured at every range of the grid.
  const std::vector<Cell> carpet = run_detectors(room("carpet_grey"));
  auto all = [](const Cell&) { return true; };
  const Tally jppc = tally(carpet, &Cell::jppc, all), dense = tally(carpet, &Cell::dense, all);
  EXPECT_GT(jppc.observed(), 70);
  EXPECT_GE(jppc.free, 0.95 * jppc.observed());
  EXPECT_GT(dense.observed(), 70);
  EXPECT_GE(dense.free, 0.95 * dense.observed());
  // Vinyl's fine speckle fades with distance: free up to 2.25 m. (Beyond,
  // JPP-C starts to fail on it and SGBM finds too few matches.)
  const std::vector<Cell> vinyl = run_detectors(room("vinyl_beige"));
  auto near = [](const Cell& c) { return c.cell.x <= 2.25; };
  const Tally near_jppc = tally(vinyl, &Cell::jppc, near), near_dense = tally(vinyl, &Cell::dense, near);
  EXPECT_GT(near_jppc.observed(), 50);
  EXPECT_GE(near_jppc.free, 0.95 * near_jppc.observed());
  EXPECT_GE(near_dense.free, 0.95 * near_dense.observed());
}

TEST(StereoOnSimulator, TexturedBoxIsDetected) {
  sim::SceneSpec spec = room();
  spec.elements.push_back(box({1.55, 0.0}, {0.3, 0.6, 0.4}, "printed_box"));
  const std::vector<Cell> cells = run_detectors(spec);
  const Tally jppc = tally(cells, &Cell::jppc, occupied);
  EXPECT_EQ(jppc.observed() + jppc.unknown, 6);  // 2 grid rows x 3 columns touch the box
  EXPECT_EQ(jppc.obstacle, 6);
  const Tally dense = tally(cells, &Cell::dense, occupied);
  EXPECT_EQ(dense.free, 0);
  EXPECT_GE(dense.obstacle, 3);  // the row that sees the front face
  // The floor in front of it stays free.
  auto in_front = [](const Cell& c) { return c.cell.x <= 1.25 && std::abs(c.cell.y) <= 0.5; };
  EXPECT_EQ(tally(cells, &Cell::jppc, in_front).obstacle, 0);
  EXPECT_EQ(tally(cells, &Cell::dense, in_front).obstacle, 0);
}

// Ground points behind a face project onto it. A texture-less (painted)
// cabinet gives zero descriptors there, which match at any disparity: JPP-C
// reads the cells inside it as free (the paper's false negatives). The
// same cabinet printed is detected.
TEST(StereoOnSimulator, JppcMissesTexturelessCabinet) {
  auto inside = [](const Cell& c) { return occupied(c) && c.cell.x >= 1.5 - 1e-6; };
  sim::SceneSpec plain = room(), printed = room();
  plain.elements.push_back(box({1.5, 0.0}, {0.5, 2.0, 0.8}, "paint_white"));
  printed.elements.push_back(box({1.5, 0.0}, {0.5, 2.0, 0.8}, "printed_box"));
  const Tally missed = tally(run_detectors(plain), &Cell::jppc, inside);
  const Tally seen = tally(run_detectors(printed), &Cell::jppc, inside);
  EXPECT_GE(missed.observed(), 12);
  EXPECT_GE(missed.free, 0.8 * missed.observed());
  EXPECT_GE(seen.obstacle, 0.9 * seen.observed());
  EXPECT_GE(seen.observed(), 12);
}

// A puddle or a polished floor mirrors the poster wall, which stereo sees at
// a virtual depth below the floor: the ground hypothesis fails and JPP-C
// reads free floor as an obstacle (the paper's false positives).
TEST(StereoOnSimulator, JppcFlagsReflectiveFloorAsObstacle) {
  auto on_patch = [](const Cell& c) { return c.cell.x >= 1.0 && c.cell.x <= 2.0 && std::abs(c.cell.y) <= 0.5; };
  const Tally dry = tally(run_detectors(room()), &Cell::jppc, on_patch);
  EXPECT_LE(dry.obstacle, 1);
  for (const auto& patch : {floor_patch(ElementSpec::Type::kPuddle, {1.6, 0.0}, {1.4, 1.4}),
                            floor_patch(ElementSpec::Type::kFloorPatch, {1.6, 0.0}, {1.4, 1.6}, "polished_stone")}) {
    sim::SceneSpec spec = room();
    spec.elements.push_back(patch);
    const std::vector<Cell> cells = run_detectors(spec);
    for (const Cell& c : cells) ASSERT_NE(c.truth, sim::TruthState::kObstacle);
    const Tally wet = tally(cells, &Cell::jppc, on_patch);
    EXPECT_GE(wet.observed(), 15) << ElementSpec::type_name(patch.type);
    EXPECT_GE(wet.obstacle, 0.75 * wet.observed()) << ElementSpec::type_name(patch.type);
  }
}

}  // namespace
}  // namespace ivoa::stereo
