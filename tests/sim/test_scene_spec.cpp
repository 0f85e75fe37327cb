// Scene files: every shipped scene loads and generates; bad input names the
// file and the key.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "ivoa/sim/scene.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "test_rig.hpp"

namespace ivoa::sim {
namespace {

std::vector<std::string> shipped_scenes() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(IVOA_SIM_SCENES_DIR))
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

std::string error_of(const std::string& yaml) {
  try {
    parse_scene_spec(yaml, "test.yaml");
  } catch (const SceneSpecError& e) {
    return e.what();
  }
  return "";
}

TEST(SimSceneSpec, ShippedScenesLoadAndGenerate) {
  const auto files = shipped_scenes();
  ASSERT_GE(files.size(), 18u);  // the nine scenes and their low_obstacles/ variants
  bool indoor = false, outdoor = false;
  for (const auto& file : files) {
    SCOPED_TRACE(file);
    const SceneSpec spec = load_scene_spec(file);
    const Scene scene = generate_scene(spec, 7);
    EXPECT_GT(scene.num_solids(), 4);
    EXPECT_GT(scene.clearance({scene.start_pose().x, scene.start_pose().y}), 0.5) << "start pose is not clear";
    EXPECT_TRUE(scene.bounds().contains(Eigen::Vector2d(scene.start_pose().x, scene.start_pose().y)));
    (spec.environment == Environment::kIndoor ? indoor : outdoor) = true;
  }
  EXPECT_TRUE(indoor && outdoor);
}

TEST(SimSceneSpec, SameSeedSameSceneOtherSeedOtherScene) {
  const SceneSpec spec = load_scene_spec(std::string(IVOA_SIM_SCENES_DIR) + "/indoor_office.yaml");
  const Scene a = generate_scene(spec, 3), b = generate_scene(spec, 3), c = generate_scene(spec, 4);
  EXPECT_EQ(a.num_solids(), b.num_solids());
  EXPECT_EQ(a.start_pose().x, b.start_pose().x);
  EXPECT_EQ(a.bounds().max(), b.bounds().max());
  EXPECT_TRUE(a.num_solids() != c.num_solids() || a.start_pose().x != c.start_pose().x);
}

TEST(SimSceneSpec, ParsesExplicitElements) {
  const SceneSpec spec = parse_scene_spec(R"(
name: exact
environment: indoor
floor: {materials: [carpet_grey]}
materials:
  - {name: my_paint, base: paint_white, color: [0.2, 0.6, 0.3]}
elements:
  - {type: wall, from: [1.2, -3], to: [1.2, 3], height: 2.4, material: my_paint, baseboard: {height: 0.1}}
  - {type: box, position: [1.5, 0.5], size: [0.4, 0.3, 0.5], yaw_deg: 30, material: printed_box}
  - {type: puddle, position: [1.0, 0], size: [0.8, 0.6]}
  - {type: pit, position: [2, 1], size: [0.5, 0.5], depth: 0.4, shape: ellipse}
  - {type: lamp_post, position: [2, -1], height: 4, intensity: 100}
start: [0, 0, 90]
)",
                                          "inline");
  EXPECT_EQ(spec.name, "exact");
  ASSERT_EQ(spec.elements.size(), 5u);
  EXPECT_EQ(spec.elements[0].type, ElementSpec::Type::kWall);
  EXPECT_DOUBLE_EQ(spec.elements[0].size.z(), 2.4);
  EXPECT_DOUBLE_EQ(spec.elements[0].baseboard_height, 0.1);
  EXPECT_NEAR(spec.elements[1].yaw, M_PI / 6, 1e-12);
  EXPECT_EQ(spec.elements[3].shape, "ellipse");
  EXPECT_DOUBLE_EQ(spec.elements[3].depth, 0.4);
  ASSERT_TRUE(spec.start.has_value());
  EXPECT_NEAR(spec.start->yaw, M_PI / 2, 1e-12);
  ASSERT_EQ(spec.materials.size(), 1u);
  EXPECT_DOUBLE_EQ(spec.materials[0].color[1], 0.6);
  EXPECT_TRUE(spec.materials[0].textureless());
  const Scene scene = generate_scene(spec, 1);
  EXPECT_EQ(scene.num_pits(), 1);
}

TEST(SimSceneSpec, ErrorsNameFileAndKey) {
  EXPECT_NE(error_of("name: x\nobstacles: {cuont: 3}\n").find("test.yaml:2: obstacles.cuont: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("walls: {materials: [paint_white, chocolate]}\n")
                .find("test.yaml:1: walls.materials[1]: unknown material 'chocolate'"),
            std::string::npos);
  EXPECT_NE(error_of("name: x\nelements:\n  - {type: box, position: [1, 0], material: unobtainium}\n")
                .find("test.yaml:3: elements[0].material: unknown material 'unobtainium'"),
            std::string::npos);
  EXPECT_NE(
      error_of("elements:\n  - {type: spaceship, position: [1, 0]}\n").find("elements[0].type: unknown element type"),
      std::string::npos);
  EXPECT_NE(error_of("layout: {width: [5, 2]}\n").find("layout.width: range [min, max] has min > max"),
            std::string::npos);
  EXPECT_NE(error_of("phenomena: {glare: 1.5}\n").find("phenomena.glare: must be a probability"), std::string::npos);
  EXPECT_NE(
      error_of("name: x\nmaterial_jitter: 1.5\n").find("test.yaml:2: material_jitter: must be in [0, 1], got 1.5"),
      std::string::npos);
  EXPECT_NE(error_of("environment: underwater\n").find("environment: expected indoor or outdoor"), std::string::npos);
  EXPECT_NE(error_of("layout: [1, 2\n").find("test.yaml:"), std::string::npos);
  EXPECT_NE(error_of("elements:\n  - {type: wall, from: [0, 0]}\n").find("wall needs from and to"), std::string::npos);
}

// An obstacle kind is one the generator can shape, from a file or from code
// (a misspelt kind once became a plain box without a word).
TEST(SimSceneSpec, UnknownObstacleKindsAreRefused) {
  EXPECT_NE(error_of("obstacles: {kinds: {box: 1, cone: 2}}\n").find("test.yaml:1: obstacles.kinds.cone: unknown key"),
            std::string::npos)
      << error_of("obstacles: {kinds: {box: 1, cone: 2}}\n");
  SceneSpec spec = parse_scene_spec("name: x\nobstacles: {count: 3}\n", "inline");
  spec.obstacles.kinds = {{"box", 1.0}, {"chiar", 1.0}};
  try {
    validate(spec);
    ADD_FAILURE() << "an unknown kind was accepted";
  } catch (const SceneSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("obstacles.kinds: unknown kind 'chiar' (one of: bench, bin,"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(generate_scene(spec, 1), SceneSpecError);
  for (const auto& kind : obstacle_kinds()) {  // each has a shape
    spec.obstacles.kinds = {{kind, 1.0}};
    EXPECT_NO_THROW(generate_scene(spec, 1)) << kind;
  }
}

// Values that parse but do not make a scene (unknown materials, ranges out of
// bounds) are placed by line too, down to the list entry.
TEST(SimSceneSpec, ValidationErrorsGiveTheLine) {
  const std::string floor = "name: x\nfloor:\n  materials:\n    - carpet_grey\n    - wood_flor\n";
  EXPECT_NE(error_of(floor).find("test.yaml:5: floor.materials[1]: unknown material 'wood_flor'"), std::string::npos)
      << error_of(floor);
  EXPECT_NE(error_of("name: x\nobstacles:\n  count: [1, 9000]\n")
                .find("test.yaml:3: obstacles.count: range [1, 9000] must lie in [0, 5000] with min <= max"),
            std::string::npos);
  const std::string door =
      "elements:\n  - {type: wall, from: [0, 3], to: [6, 3],\n     doors: [{offset: 2}, {offset: 4, material: "
      "jelly}]}\n";
  EXPECT_NE(error_of(door).find("test.yaml:3: elements[0].doors[1].material: unknown material 'jelly'"),
            std::string::npos)
      << error_of(door);
  const std::string empty = "name: x\nobstacles: {count: 3, materials: []}\n";
  EXPECT_NE(error_of(empty).find("test.yaml:2: obstacles.materials: needs at least one material"), std::string::npos)
      << error_of(empty);
}

// Values that would crash or exhaust the simulator are refused by name:
// NaN and infinities pass any comparison, an empty wall palette divided by
// zero, a huge texture scale or position ran out of memory.
TEST(SimSceneSpec, RefusesWhatCannotBeBuilt) {
  const auto expect_error = [](const std::string& yaml, const std::string& message) {
    EXPECT_NE(error_of(yaml).find(message), std::string::npos) << yaml << " -> " << error_of(yaml);
  };
  expect_error("layout: {width: [.nan, 5]}\n", "test.yaml:1: layout.width[0]: expected a finite number, got '.nan'");
  expect_error("lighting: {ambient: .inf}\n", "lighting.ambient: expected a finite number");
  expect_error("materials:\n  - {name: m, color: [0.5, .nan, 0.5]}\n", "materials[0].color[1]: expected a finite");
  expect_error("start: [0, 0, .nan]\n", "start[2]: expected a finite number");
  expect_error("layout: {type: room}\nwalls: {materials: []}\n",
               "walls.materials: needs at least one material: a room, corridor or office");
  expect_error("materials:\n  - {name: m, scale: 1e9}\n", "test.yaml:2: materials[0].scale: must be in [0.0001, 100]");
  expect_error("materials:\n  - {name: m, emission: -5}\n", "materials[0].emission: must be in [0, 10000]");
  expect_error("elements:\n  - {type: box, position: [1e12, 0]}\n",
               "elements[0].position: coordinates must lie within 1000 m");
  expect_error("elements:\n  - {type: box, position: [1, 0], size: [1, 1, 1e6]}\n", "sizes must be in [0, 100] m");
  expect_error("lighting: {sun_irradiance: -10}\n",
               "lighting.sun_irradiance: range [-10, -10] must lie in [0, 100000]");
  expect_error("name: x\nobstacles: {count: 3, count: 4}\n", "test.yaml:2: obstacles.count: given twice");
  expect_error("name: x\n? [a, b]\n: 3\n", "a key must be a plain name");
  // Outdoor scenes and bare layouts have no wall palette and need none.
  EXPECT_EQ(error_of("layout: {type: none}\nwalls: {materials: []}\n"), "");
}

// The format example in the scenes README is a valid scene.
TEST(SimSceneSpec, ReadmeExampleParses) {
  std::ifstream in(std::string(IVOA_SIM_SCENES_DIR) + "/README.md");
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const size_t start = text.find("```yaml\n");
  ASSERT_NE(start, std::string::npos);
  const size_t end = text.find("```", start + 8);
  const SceneSpec spec = parse_scene_spec(text.substr(start + 8, end - start - 8), "README.md");
  EXPECT_EQ(spec.elements.size(), 14u);
  EXPECT_EQ(spec.materials.size(), 2u);
  const Scene scene = generate_scene(spec, 1);
  EXPECT_GT(scene.num_solids(), 20);
  EXPECT_EQ(scene.num_pits(), 1);
}

TEST(SimSceneSpec, MissingFileIsNamed) {
  try {
    load_scene_spec("/nonexistent/scene.yaml");
    FAIL() << "no exception";
  } catch (const SceneSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
  ivoa::test::TempDir dir;
  std::ofstream(dir.file("bad.yaml")) << "floor: {materials: [marshmallow]}\n";
  try {
    load_scene_spec(dir.file("bad.yaml"));
    FAIL() << "no exception";
  } catch (const SceneSpecError& e) {
    EXPECT_NE(
        std::string(e.what()).find(dir.file("bad.yaml") + ":1: floor.materials[0]: unknown material 'marshmallow'"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ivoa::sim
