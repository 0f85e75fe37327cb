#pragma once
// Counterfactual scenes: the same scene with one stereo-failure phenomenon
// taken away and everything else (layout, geometry, lights' places, the
// robot's trajectory) unchanged. Rendering the same pose in both and
// re-running a stereo detector tells which phenomenon *causes* a failure,
// where the ground-truth flags only say which phenomena are present.
#include <cstdint>
#include <optional>
#include <vector>

#include "ivoa/sim/scene.hpp"
#include "ivoa/sim/scene_spec.hpp"

namespace ivoa::sim {

// How each phenomenon (a sim_ground_truth_t::PHENOMENON_* bit) is taken away:
//   REFLECTION    every material loses its mirror reflectance (wet surfaces
//                 stay darker: only the reflection goes);
//   GLARE         light sources are not seen: ceiling panels still light
//                 the room but their faces show ceiling tiles (so floors
//                 mirror tiles), lamps lose their highlight lobes; the low
//                 sun outdoors stays;
//   DARK_STRIPE   dark baseboards take the wall's own material;
//   TEXTURELESS   texture-less materials of the floor, floor features and
//                 solids get a plaster texture of their own colour
//                 (contrast 0.3); light-emitting ones stay;
//   REPETITIVE    periodic materials of the same get a plaster texture of
//                 the same colours and contrast instead of their pattern
//                 (the ceiling, a precomputed map, stays);
//   LOW_LIGHT     a low-light session is lit at full level (the same scene:
//                 the generator draws the same random numbers).
// SATURATED is an outcome of the exposure, not of the scene: not removable.
std::vector<uint8_t> removable_phenomena();

// The scene generate_scene(spec, seed) gives, without `phenomena` (one
// PHENOMENON_* bit, or several OR-ed: all of them taken away); empty when
// that scene carries none of them (the twin would be identical). Throws
// std::invalid_argument for bits removable_phenomena() does not list and
// SceneSpecError for an invalid spec.
std::optional<Scene> generate_scene_without(const SceneSpec& spec, uint64_t seed, uint8_t phenomena);

}  // namespace ivoa::sim
