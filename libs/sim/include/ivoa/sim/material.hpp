#pragma once
// Surface materials: colour, texture pattern, gloss and what the depth
// sensor sees. A library of named materials ships with the simulator; scene
// files can add their own, derived from a library material.
#include <array>
#include <string>
#include <vector>

namespace ivoa::sim {

// The texture a material is synthesised with (tileable maps, built once per scene).
enum class Pattern {
  kUniform,       // flat paint: no texture at all (stereo has nothing to match)
  kPlaster,       // multi-scale blotches (plaster, concrete, stone)
  kCarpet,        // fine fibre noise with mottling
  kSpeckle,       // fine speckle with dots (vinyl, terrazzo, gravel)
  kAsphalt,       // dark matrix with bright aggregate
  kTiles,         // square tiles and grout lines (periodic)
  kChecker,       // alternating tiles (strongly periodic)
  kBricks,        // running-bond bricks and mortar (periodic)
  kWood,          // planks with grain
  kFabric,        // woven cloth
  kMetal,         // brushed metal (anisotropic fine lines)
  kCardboard,     // cardboard with fibres
  kGrass,         // grass / hedge
  kStripes,       // vertical stripes (wallpaper), periodic
  kFacade,        // building facade with a grid of windows, periodic
  kCeilingTiles,  // suspended ceiling grid
  kPrinted,       // busy printed graphics (labels, posters): strong texture
};

using Rgb = std::array<double, 3>;  // sRGB components in [0, 1]

struct Material {
  std::string name;
  Pattern pattern = Pattern::kUniform;
  Rgb color{0.5, 0.5, 0.5};   // base albedo colour (sRGB)
  Rgb color2{0.3, 0.3, 0.3};  // secondary colour: grout, mortar, specks, stripes, windows
  double contrast = 0.0;      // texture amplitude, 0 (uniform) .. 1
  double scale = 0.3;         // metres: tile / brick / plank size, or the feature size of noise
  double reflectance = 0.0;   // mirror reflectance at normal incidence (Fresnel F0): water 0.02, polish 0.05
  double roughness = 0.0;     // radians of blur of the mirror image (0 = perfect mirror)
  double wetness = 0.0;       // 0..1: a water film darkens the diffuse colour
  double ir_albedo = -1.0;    // depth-sensor return 0..1; < 0 means "from the colour's luminance"
  double emission = 0.0;      // radiance of a light-emitting surface (lamp panels), 0 = not a light

  bool textureless() const { return pattern == Pattern::kUniform || contrast < 0.03; }
  bool repetitive() const;
  bool reflective() const { return reflectance > 0.0; }
};

// The built-in library. Throws std::out_of_range naming the material.
const Material& builtin_material(const std::string& name);
bool has_builtin_material(const std::string& name);

Pattern pattern_from_string(const std::string& name);  // throws std::invalid_argument
const char* to_string(Pattern pattern);

}  // namespace ivoa::sim
