// Counterfactual twins: each takes away exactly one phenomenon. The geometry
// (surfaces and depths the camera sees) stays the same; the phenomenon's
// ground-truth pixels go; a scene without the phenomenon has no twin.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "ivoa/sim/counterfactual.hpp"
#include "ivoa/sim/elements.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::sim {
namespace {

using namespace elements;
using GT = sim_ground_truth_t;

// Mirroring tiles, a texture-less wall on a black baseboard, a glaring panel.
SceneSpec many_phenomena() {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "tile_white");
  spec.elements.push_back(wall({7.0, -4}, {7.0, 4}, "paint_white", 2.5, 0.12, "baseboard_black"));
  spec.elements.push_back(ceiling_light({4.5, 0.0}, {0.6, 0.6}, 400));
  return spec;
}

// Dull carpet, a plaster wall without baseboard, normal light.
SceneSpec few_phenomena() {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
  spec.elements.push_back(wall({4.0, -4}, {4.0, 4}, "plaster"));
  return spec;
}

SceneSpec dim_room() {
  SceneSpec spec = make_bare_spec(Environment::kIndoor, "tile_white");
  spec.elements.push_back(wall({7.0, -4}, {7.0, 4}, "paint_white"));
  spec.lighting.low_light_factor = Range(0.003);
  spec.phenomena.low_light = 1.0;
  return spec;
}

int pixels_with(const SimFrame& f, uint8_t bit) { return cv::countNonZero((f.truth_phenomena & bit) != 0); }

void expect_same_geometry(const SimFrame& a, const SimFrame& b) {
  EXPECT_EQ(cv::countNonZero(a.truth_surface != b.truth_surface), 0);
  cv::Mat diff;
  cv::absdiff(a.truth_depth, b.truth_depth, diff);
  diff.setTo(0, a.truth_depth == std::numeric_limits<float>::infinity());
  double max_diff = 0;
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LT(max_diff, 1e-6);
}

TEST(SimCounterfactual, EachTwinTakesAwayItsPhenomenonAndKeepsTheGeometry) {
  const SceneSpec spec = many_phenomena();
  const SimFrame factual = Simulator(generate_scene(spec, 1)).render(Pose2D{}, 0);
  for (const uint8_t bit : {GT::PHENOMENON_REFLECTION, GT::PHENOMENON_GLARE, GT::PHENOMENON_DARK_STRIPE,
                            GT::PHENOMENON_TEXTURELESS, GT::PHENOMENON_REPETITIVE}) {
    SCOPED_TRACE(int{bit});
    ASSERT_GT(pixels_with(factual, bit), 100) << "the scene shows it";
    const std::optional<Scene> twin = generate_scene_without(spec, 1, bit);
    ASSERT_TRUE(twin.has_value());
    const SimFrame without = Simulator(*twin).render(Pose2D{}, 0);
    EXPECT_LT(pixels_with(without, bit), 0.02 * pixels_with(factual, bit));
    expect_same_geometry(factual, without);
    EXPECT_GT(cv::norm(factual.left, without.left, cv::NORM_L1), 0) << "the image changes";
  }
}

TEST(SimCounterfactual, OtherPhenomenaStay) {
  const SceneSpec spec = many_phenomena();
  const SimFrame factual = Simulator(generate_scene(spec, 1)).render(Pose2D{}, 0);
  const SimFrame no_stripe =
      Simulator(*generate_scene_without(spec, 1, GT::PHENOMENON_DARK_STRIPE)).render(Pose2D{}, 0);
  // The black baseboard was texture-less too; it becomes painted wall, still texture-less.
  EXPECT_EQ(pixels_with(no_stripe, GT::PHENOMENON_TEXTURELESS), pixels_with(factual, GT::PHENOMENON_TEXTURELESS));
  EXPECT_EQ(pixels_with(no_stripe, GT::PHENOMENON_REPETITIVE), pixels_with(factual, GT::PHENOMENON_REPETITIVE));
}

TEST(SimCounterfactual, SeveralAtOnce) {
  const SceneSpec spec = many_phenomena();
  const SimFrame factual = Simulator(generate_scene(spec, 1)).render(Pose2D{}, 0);
  const uint8_t removed = GT::PHENOMENON_REFLECTION | GT::PHENOMENON_DARK_STRIPE | GT::PHENOMENON_TEXTURELESS;
  const SimFrame without = Simulator(*generate_scene_without(spec, 1, removed)).render(Pose2D{}, 0);
  for (const uint8_t bit : {GT::PHENOMENON_REFLECTION, GT::PHENOMENON_DARK_STRIPE, GT::PHENOMENON_TEXTURELESS})
    EXPECT_LT(pixels_with(without, bit), 0.02 * pixels_with(factual, bit)) << int{bit};
  EXPECT_GT(pixels_with(without, GT::PHENOMENON_REPETITIVE), 0.9 * pixels_with(factual, GT::PHENOMENON_REPETITIVE));
  expect_same_geometry(factual, without);
  // Removing what a scene lacks together with nothing else still changes nothing.
  EXPECT_FALSE(generate_scene_without(few_phenomena(), 1, GT::PHENOMENON_DARK_STRIPE | GT::PHENOMENON_LOW_LIGHT));
}

TEST(SimCounterfactual, LowLightTwinIsTheSameSceneAtFullLight) {
  const SceneSpec spec = dim_room();
  const SimFrame dim = Simulator(generate_scene(spec, 1)).render(Pose2D{}, 0);
  const std::optional<Scene> lit = generate_scene_without(spec, 1, GT::PHENOMENON_LOW_LIGHT);
  ASSERT_TRUE(lit.has_value());
  const SimFrame bright = Simulator(*lit).render(Pose2D{}, 0);
  EXPECT_GT(pixels_with(dim, GT::PHENOMENON_LOW_LIGHT), 0.5 * static_cast<double>(dim.truth_phenomena.total()));
  EXPECT_LT(pixels_with(bright, GT::PHENOMENON_LOW_LIGHT), 0.05 * static_cast<double>(dim.truth_phenomena.total()));
  expect_same_geometry(dim, bright);
}

TEST(SimCounterfactual, NoTwinForWhatTheSceneDoesNotCarry) {
  const SceneSpec spec = few_phenomena();
  for (const uint8_t bit : removable_phenomena()) {
    SCOPED_TRACE(int{bit});
    if (bit == GT::PHENOMENON_GLARE) continue;  // every room has ceiling panels
    EXPECT_FALSE(generate_scene_without(spec, 1, bit).has_value());
  }
}

TEST(SimCounterfactual, SaturationCannotBeTakenAway) {
  EXPECT_THROW(generate_scene_without(few_phenomena(), 1, GT::PHENOMENON_SATURATED), std::invalid_argument);
  EXPECT_THROW(generate_scene_without(few_phenomena(), 1, GT::PHENOMENON_SATURATED | GT::PHENOMENON_REFLECTION),
               std::invalid_argument);
  EXPECT_THROW(generate_scene_without(few_phenomena(), 1, 0), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa::sim
