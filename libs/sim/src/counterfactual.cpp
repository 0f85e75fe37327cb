#include "ivoa/sim/counterfactual.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ivoa/sim_ground_truth_t.hpp"
#include "scene_builder.hpp"
#include "scene_data.hpp"

namespace ivoa::sim {
namespace {

using GT = sim_ground_truth_t;
using detail::MaterialData;
using detail::SceneData;

// Replaces material `m` by the same material drawn with a plaster texture.
MaterialData plaster_version(const MaterialData& m, double contrast, double scale) {
  Material spec = m.spec;
  spec.name += "+plaster";  // a texture cache key of its own
  spec.pattern = Pattern::kPlaster;
  spec.contrast = contrast;
  spec.scale = scale;
  MaterialData out = detail::make_material_data(spec);
  out.emission = m.emission;  // keep the (low-light scaled) emission
  return out;
}

bool remove_reflection(SceneData& d) {
  bool changed = false;
  for (MaterialData& m : d.materials)
    if (m.f0 > 0) m.f0 = 0, changed = true;
  return changed;
}

bool remove_dark_stripes(SceneData& d) {
  bool changed = false;
  for (detail::Prism& p : d.prisms)
    if (p.base_height > 0 && (d.materials[p.base_material].phenomena & GT::PHENOMENON_DARK_STRIPE)) {
      p.base_material = p.material;
      changed = true;
    }
  return changed;
}

// Materials the renderer shades from their texture: the floor's, floor
// features' and prisms'. (The ceiling is a precomputed radiance map.)
std::vector<bool> shaded_materials(const SceneData& d) {
  std::vector<bool> used(d.materials.size(), false);
  used[d.floor_material] = true;
  for (const detail::FloorFeature& f : d.floor_features) used[f.material] = true;
  for (const detail::Prism& p : d.prisms) used[p.material] = used[p.top_material] = used[p.base_material] = true;
  return used;
}

// Gives the shaded materials that carry `phenomenon` (light-emitting ones
// excepted) a plaster texture: of `contrast` with 0.3 m features, or of their
// own contrast and scale where contrast < 0.
bool replace_with_plaster(SceneData& d, uint8_t phenomenon, double contrast) {
  bool changed = false;
  const std::vector<bool> shaded = shaded_materials(d);
  for (size_t i = 0; i < d.materials.size(); ++i) {
    MaterialData& m = d.materials[i];
    if (shaded[i] && (m.phenomena & phenomenon) && m.spec.emission <= 0) {
      m = contrast < 0 ? plaster_version(m, m.spec.contrast, m.spec.scale) : plaster_version(m, contrast, 0.3);
      changed = true;
    }
  }
  return changed;
}

bool remove_texturelessness(SceneData& d) { return replace_with_plaster(d, GT::PHENOMENON_TEXTURELESS, 0.3); }
bool remove_repetition(SceneData& d) { return replace_with_plaster(d, GT::PHENOMENON_REPETITIVE, -1); }

// Glare is the mirror image of a light source: the ceiling panels' bright
// faces (drawn into the ceiling's radiance map) and the highlight lobes of
// lamps. The panels still light the room; their faces show ceiling tiles.
// (Outdoors, the low sun's glare stays: the sun cannot be moved without
// changing the lighting.)
bool hide_light_sources(detail::SceneBuilder& b) {
  bool changed = !b.panels().empty();
  b.panels().clear();
  for (detail::PointLight& l : b.data().lights)
    if (l.glare > 0) l.glare = 0, changed = true;
  return changed;
}

// The generator draws the low-light factor whenever a session is dim; a
// factor of 1 keeps every other draw, and so the scene, the same.
bool light_fully(const SceneSpec& spec, uint64_t seed, SceneSpec& lit) {
  if (generate_scene(spec, seed).data().light_level >= 1) return false;
  lit.lighting.low_light_factor = Range(1, 1);
  return true;
}

constexpr uint8_t kRemovable = GT::PHENOMENON_REFLECTION | GT::PHENOMENON_TEXTURELESS | GT::PHENOMENON_GLARE |
                               GT::PHENOMENON_DARK_STRIPE | GT::PHENOMENON_REPETITIVE | GT::PHENOMENON_LOW_LIGHT;

}  // namespace

std::vector<uint8_t> removable_phenomena() {
  return {GT::PHENOMENON_REFLECTION,  GT::PHENOMENON_TEXTURELESS, GT::PHENOMENON_GLARE,
          GT::PHENOMENON_DARK_STRIPE, GT::PHENOMENON_REPETITIVE,  GT::PHENOMENON_LOW_LIGHT};
}

std::optional<Scene> generate_scene_without(const SceneSpec& spec, uint64_t seed, uint8_t phenomena) {
  if (phenomena == 0 || (phenomena & ~kRemovable) != 0)
    throw std::invalid_argument("phenomena " + std::to_string(phenomena) +
                                ": not a set of removable phenomena (reflection 1, textureless 2, glare 4, dark "
                                "stripe 8, repetitive 16, low light 32; saturation cannot be taken away)");
  SceneSpec edited = spec;
  bool changed = (phenomena & GT::PHENOMENON_LOW_LIGHT) && light_fully(spec, seed, edited);
  std::shared_ptr<SceneData> data = detail::build_scene(edited, seed, [&](detail::SceneBuilder& b) {
    if (phenomena & GT::PHENOMENON_GLARE) changed |= hide_light_sources(b);
  });
  // Material edits after the light maps: they change how surfaces look, not how they are lit.
  if (phenomena & GT::PHENOMENON_REFLECTION) changed |= remove_reflection(*data);
  if (phenomena & GT::PHENOMENON_DARK_STRIPE) changed |= remove_dark_stripes(*data);
  if (phenomena & GT::PHENOMENON_TEXTURELESS) changed |= remove_texturelessness(*data);
  if (phenomena & GT::PHENOMENON_REPETITIVE) changed |= remove_repetition(*data);
  if (!changed) return std::nullopt;
  return Scene(std::move(data));
}

}  // namespace ivoa::sim
