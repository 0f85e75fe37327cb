#pragma once
// The internal form of a generated scene, laid out for the renderer: flat
// arrays of small structs, material indices instead of names, light maps.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "color.hpp"
#include "ivoa/sim/material.hpp"
#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "texture.hpp"

namespace ivoa::sim::detail {

struct MaterialData {
  Material spec;
  std::shared_ptr<const Texture> texture;
  Rgbf emission;            // linear radiance added to the surface (lights)
  float f0 = 0;             // mirror reflectance at normal incidence
  float roughness = 0;      // radians
  float diffuse_scale = 1;  // < 1 on wet surfaces
  float ir_albedo = 0.5f;   // depth-sensor return
  uint8_t phenomena = 0;    // PHENOMENON_TEXTURELESS / REPETITIVE / DARK_STRIPE the surface carries
};

// A vertical prism: an oriented rectangle or a circle on the ground plane,
// extruded over [z0, z1]. Walls, boxes, cylinders, chair and table parts,
// curbs, poles: everything that stands in the scene.
struct Prism {
  enum Shape : uint8_t { kRect = 0, kCircle = 1 };
  Shape shape = kRect;
  uint8_t surface = 0;   // sim_ground_truth_t::SURFACE_*
  float cx = 0, cy = 0;  // centre, world
  float hx = 0, hy = 0;  // half extents along the local axes (circle: radius in hx)
  float cos_yaw = 1, sin_yaw = 0;
  float z0 = 0, z1 = 0;
  uint16_t material = 0, top_material = 0, base_material = 0;
  float base_height = 0;  // below this height the side uses base_material (baseboard)
  float u_offset = 0, v_offset = 0;
  Rgbf tint{1, 1, 1};
  // Lighting, precomputed at the prism: irradiance(n) = ambient + max(0, n . light_dir) * directional
  Rgbf ambient, directional;
  Eigen::Vector3f light_dir{0, 0, 1};
  float sun_visibility = 1;  // fraction of the prism the sun reaches (0 in another's shadow)
  float radius() const { return shape == kCircle ? hx : std::sqrt(hx * hx + hy * hy); }
};

// Regions of the floor: patches of another material, puddles, pits.
struct FloorFeature {
  enum Kind : uint8_t { kPatch, kPuddle, kPit };
  Kind kind = kPatch;
  bool ellipse = false;
  uint16_t material = 0;
  float cx = 0, cy = 0, hx = 0, hy = 0, cos_yaw = 1, sin_yaw = 0;
  float depth = 0;  // pits
  int mask = -1;    // puddles: index into SceneData::puddle_masks
};

// A puddle's outline: a smooth field over its box, water where > 0.
struct PuddleMask {
  int nx = 0, ny = 0;
  float cell = 0.02f;
  std::vector<float> field;
};

struct PointLight {
  Eigen::Vector3f position;
  Rgbf intensity;        // radiant intensity straight down (panels) or all around (bulbs)
  bool downward = true;  // a ceiling panel / lamp head: cosine falloff around -z
  float glare = 0;       // > 0: small bright source that makes a specular highlight lobe
};

struct SkyData {
  Rgbf zenith{0.3f, 0.45f, 0.8f}, horizon{0.7f, 0.75f, 0.85f};
  bool has_sun = false;
  Eigen::Vector3f sun_dir{0, 0, 1};  // towards the sun
  Rgbf sun_irradiance;
  float sun_radius = 0.0047f;  // radians
};

// Uniform grid over the floor plan listing the floor features overlapping
// each cell, in paint order (later ones lie on top).
struct PlanGrid {
  float x0 = 0, y0 = 0, cell = 1, inv_cell = 1;
  int nx = 0, ny = 0;
  std::vector<uint32_t> feature_start;
  std::vector<uint16_t> features;
  bool inside(float x, float y) const { return x >= x0 && y >= y0 && x < x0 + cell * nx && y < y0 + cell * ny; }
  int index(float x, float y) const {
    return static_cast<int>((y - y0) * inv_cell) * nx + static_cast<int>((x - x0) * inv_cell);
  }
};

struct SceneData {
  std::string name;
  uint64_t seed = 0;
  Environment environment = Environment::kIndoor;
  std::vector<MaterialData> materials;
  std::vector<Prism> prisms;
  uint16_t floor_material = 0;
  std::vector<FloorFeature> floor_features;
  std::vector<PuddleMask> puddle_masks;
  std::vector<PointLight> lights;
  Rgbf ambient{0.5f, 0.5f, 0.5f};  // irradiance from bounced light (indoor) or the sky (outdoor)
  PlanGrid grid;

  // Lighting of the ground: irradiance (with contact shadows and sun shadows)
  // and the fraction of direct sun each ground point receives.
  RadianceMap floor_irradiance;
  Rgbf floor_irradiance_outside;
  ScalarMap floor_sunlit;
  Rgbf pit_irradiance;

  bool has_ceiling = false;
  float ceiling_height = 3.0f;
  RadianceMap ceiling_radiance;  // what the ceiling looks like (panels glow), mip-mapped
  SkyData sky;
  float light_level = 1;  // scene brightness factor (low-light sessions < 1)
  float max_exposure_scale = 1;

  Eigen::AlignedBox2d bounds;
  Pose2D start;
};

// Precomputes prism lighting, the floor light map, sun visibility and the
// ceiling's radiance map (scene_lighting.cpp).
void compute_lighting(SceneData& scene);
// Builds the plan grid (scene.cpp).
void build_plan_grid(SceneData& scene);

}  // namespace ivoa::sim::detail
