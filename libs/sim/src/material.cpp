#include "ivoa/sim/material.hpp"

#include <map>
#include <stdexcept>

namespace ivoa::sim {
namespace {

struct Entry {
  const char* name;
  Pattern pattern;
  Rgb color, color2;
  double contrast, scale, reflectance, roughness, wetness, ir_albedo, emission;
};

// Colours are sRGB; reflectance is Fresnel F0 (water 0.02, wax / polish ~0.05).
// Roughness is the blur of the mirror image in radians.
const Entry kLibrary[] = {
    // Indoor floors.
    {"carpet_grey", Pattern::kCarpet, {0.42, 0.42, 0.44}, {0.28, 0.28, 0.30}, 0.55, 0.004, 0, 0, 0, -1, 0},
    {"carpet_blue", Pattern::kCarpet, {0.22, 0.28, 0.42}, {0.12, 0.16, 0.28}, 0.55, 0.004, 0, 0, 0, -1, 0},
    {"carpet_brown", Pattern::kCarpet, {0.40, 0.31, 0.22}, {0.25, 0.18, 0.12}, 0.5, 0.005, 0, 0, 0, -1, 0},
    {"rug_red", Pattern::kFabric, {0.55, 0.14, 0.12}, {0.80, 0.62, 0.30}, 0.6, 0.012, 0, 0, 0, -1, 0},
    {"tile_white", Pattern::kTiles, {0.82, 0.81, 0.77}, {0.48, 0.47, 0.44}, 0.25, 0.30, 0.04, 0.05, 0, -1, 0},
    {"tile_beige_small", Pattern::kTiles, {0.74, 0.66, 0.54}, {0.45, 0.40, 0.33}, 0.3, 0.15, 0.03, 0.08, 0, -1, 0},
    {"tile_checker", Pattern::kChecker, {0.86, 0.86, 0.84}, {0.10, 0.10, 0.11}, 0.9, 0.30, 0.04, 0.05, 0, -1, 0},
    {"vinyl_beige", Pattern::kSpeckle, {0.72, 0.68, 0.60}, {0.45, 0.42, 0.38}, 0.3, 0.006, 0.03, 0.10, 0, -1, 0},
    {"polished_concrete", Pattern::kPlaster, {0.58, 0.57, 0.55}, {0.45, 0.44, 0.43}, 0.10, 0.15, 0.05, 0.02, 0, -1, 0},
    {"polished_stone", Pattern::kPlaster, {0.78, 0.75, 0.70}, {0.55, 0.52, 0.48}, 0.14, 0.06, 0.06, 0.012, 0, -1, 0},
    {"epoxy_grey", Pattern::kUniform, {0.55, 0.57, 0.58}, {0.55, 0.57, 0.58}, 0.0, 1.0, 0.05, 0.02, 0, -1, 0},
    {"wood_floor", Pattern::kWood, {0.55, 0.38, 0.22}, {0.38, 0.24, 0.13}, 0.45, 0.14, 0.03, 0.08, 0, -1, 0},
    {"water", Pattern::kUniform, {0.07, 0.07, 0.08}, {0.07, 0.07, 0.08}, 0.0, 1.0, 0.02, 0.004, 1.0, 0.25, 0},
    // Walls, baseboards, doors, ceiling.
    {"paint_white", Pattern::kUniform, {0.86, 0.86, 0.83}, {0.86, 0.86, 0.83}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"paint_beige", Pattern::kUniform, {0.80, 0.74, 0.62}, {0.80, 0.74, 0.62}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"paint_grey", Pattern::kUniform, {0.62, 0.63, 0.64}, {0.62, 0.63, 0.64}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"paint_blue", Pattern::kUniform, {0.45, 0.58, 0.72}, {0.45, 0.58, 0.72}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"paint_green", Pattern::kUniform, {0.58, 0.70, 0.55}, {0.58, 0.70, 0.55}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plaster", Pattern::kPlaster, {0.80, 0.78, 0.72}, {0.55, 0.53, 0.48}, 0.28, 0.04, 0, 0, 0, -1, 0},
    {"wallpaper_stripes", Pattern::kStripes, {0.80, 0.76, 0.66}, {0.55, 0.45, 0.35}, 0.5, 0.05, 0, 0, 0, -1, 0},
    {"brick_red", Pattern::kBricks, {0.55, 0.26, 0.18}, {0.70, 0.68, 0.62}, 0.55, 0.22, 0, 0, 0, -1, 0},
    {"concrete_block", Pattern::kBricks, {0.62, 0.62, 0.60}, {0.45, 0.45, 0.44}, 0.35, 0.40, 0, 0, 0, -1, 0},
    {"wood_panel", Pattern::kWood, {0.62, 0.45, 0.28}, {0.45, 0.30, 0.17}, 0.4, 0.20, 0, 0, 0, -1, 0},
    {"poster_wall", Pattern::kPrinted, {0.70, 0.68, 0.64}, {0.20, 0.30, 0.55}, 0.8, 0.08, 0, 0, 0, -1, 0},
    {"baseboard_black", Pattern::kUniform, {0.04, 0.04, 0.045}, {0.04, 0.04, 0.045}, 0.0, 1.0, 0, 0, 0, 0.04, 0},
    {"baseboard_dark_grey", Pattern::kUniform, {0.09, 0.09, 0.10}, {0.09, 0.09, 0.10}, 0.0, 1.0, 0, 0, 0, 0.08, 0},
    {"baseboard_brown", Pattern::kWood, {0.16, 0.09, 0.05}, {0.10, 0.06, 0.03}, 0.15, 0.2, 0, 0, 0, 0.10, 0},
    {"door_wood", Pattern::kWood, {0.48, 0.32, 0.19}, {0.34, 0.21, 0.11}, 0.4, 0.9, 0, 0, 0, -1, 0},
    {"door_grey", Pattern::kUniform, {0.55, 0.56, 0.58}, {0.55, 0.56, 0.58}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"ceiling_tiles", Pattern::kCeilingTiles, {0.85, 0.85, 0.83}, {0.60, 0.60, 0.60}, 0.3, 0.60, 0, 0, 0, -1, 0},
    {"light_panel", Pattern::kUniform, {0.95, 0.95, 0.95}, {0.95, 0.95, 0.95}, 0.0, 1.0, 0, 0, 0, -1, 80},
    // Indoor objects.
    {"cardboard", Pattern::kCardboard, {0.62, 0.46, 0.30}, {0.45, 0.32, 0.20}, 0.35, 0.02, 0, 0, 0, -1, 0},
    {"printed_box", Pattern::kPrinted, {0.85, 0.83, 0.78}, {0.75, 0.15, 0.10}, 0.9, 0.06, 0, 0, 0, -1, 0},
    {"plastic_blue", Pattern::kUniform, {0.10, 0.25, 0.62}, {0.10, 0.25, 0.62}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plastic_red", Pattern::kUniform, {0.70, 0.10, 0.08}, {0.70, 0.10, 0.08}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plastic_yellow", Pattern::kUniform, {0.85, 0.70, 0.10}, {0.85, 0.70, 0.10}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plastic_green", Pattern::kUniform, {0.15, 0.45, 0.20}, {0.15, 0.45, 0.20}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plastic_white", Pattern::kUniform, {0.88, 0.88, 0.86}, {0.88, 0.88, 0.86}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"plastic_black", Pattern::kUniform, {0.05, 0.05, 0.05}, {0.05, 0.05, 0.05}, 0.0, 1.0, 0, 0, 0, 0.05, 0},
    {"fabric_grey", Pattern::kFabric, {0.35, 0.36, 0.38}, {0.22, 0.23, 0.25}, 0.4, 0.004, 0, 0, 0, -1, 0},
    {"fabric_blue", Pattern::kFabric, {0.15, 0.22, 0.40}, {0.08, 0.12, 0.25}, 0.4, 0.004, 0, 0, 0, -1, 0},
    {"metal_grey", Pattern::kMetal, {0.55, 0.56, 0.58}, {0.40, 0.41, 0.43}, 0.12, 0.01, 0, 0, 0, -1, 0},
    {"metal_black", Pattern::kMetal, {0.08, 0.08, 0.09}, {0.05, 0.05, 0.05}, 0.1, 0.01, 0, 0, 0, 0.06, 0},
    {"wood_light", Pattern::kWood, {0.70, 0.55, 0.38}, {0.55, 0.40, 0.25}, 0.35, 0.12, 0, 0, 0, -1, 0},
    // Outdoor ground.
    {"asphalt", Pattern::kAsphalt, {0.22, 0.22, 0.23}, {0.45, 0.44, 0.43}, 0.45, 0.006, 0, 0, 0, -1, 0},
    {"asphalt_wet", Pattern::kAsphalt, {0.22, 0.22, 0.23}, {0.45, 0.44, 0.43}, 0.45, 0.006, 0.03, 0.03, 0.6, -1, 0},
    {"concrete", Pattern::kPlaster, {0.62, 0.61, 0.58}, {0.45, 0.44, 0.42}, 0.3, 0.03, 0, 0, 0, -1, 0},
    {"concrete_wet", Pattern::kPlaster, {0.62, 0.61, 0.58}, {0.45, 0.44, 0.42}, 0.3, 0.03, 0.03, 0.03, 0.5, -1, 0},
    {"concrete_slabs", Pattern::kTiles, {0.64, 0.63, 0.60}, {0.38, 0.37, 0.35}, 0.3, 1.2, 0, 0, 0, -1, 0},
    {"paving_red", Pattern::kBricks, {0.55, 0.30, 0.24}, {0.40, 0.38, 0.35}, 0.4, 0.20, 0, 0, 0, -1, 0},
    {"paving_grey", Pattern::kBricks, {0.55, 0.55, 0.53}, {0.35, 0.35, 0.34}, 0.35, 0.20, 0, 0, 0, -1, 0},
    {"paving_wet", Pattern::kBricks, {0.55, 0.55, 0.53}, {0.35, 0.35, 0.34}, 0.35, 0.20, 0.03, 0.035, 0.5, -1, 0},
    {"tile_outdoor", Pattern::kTiles, {0.70, 0.66, 0.60}, {0.42, 0.40, 0.36}, 0.3, 0.40, 0, 0, 0, -1, 0},
    {"gravel", Pattern::kSpeckle, {0.50, 0.47, 0.42}, {0.75, 0.72, 0.66}, 0.7, 0.015, 0, 0, 0, -1, 0},
    {"grass", Pattern::kGrass, {0.22, 0.38, 0.12}, {0.40, 0.50, 0.20}, 0.6, 0.01, 0, 0, 0, -1, 0},
    {"soil", Pattern::kSpeckle, {0.30, 0.22, 0.15}, {0.20, 0.15, 0.10}, 0.5, 0.01, 0, 0, 0, -1, 0},
    // Outdoor objects and backdrops.
    {"facade_windows", Pattern::kFacade, {0.72, 0.66, 0.58}, {0.12, 0.14, 0.18}, 0.8, 1.6, 0, 0, 0, -1, 0},
    {"facade_concrete", Pattern::kPlaster, {0.66, 0.64, 0.60}, {0.50, 0.48, 0.45}, 0.2, 0.3, 0, 0, 0, -1, 0},
    {"hedge", Pattern::kGrass, {0.12, 0.25, 0.08}, {0.25, 0.40, 0.12}, 0.7, 0.03, 0, 0, 0, -1, 0},
    {"curb_concrete", Pattern::kPlaster, {0.70, 0.69, 0.66}, {0.50, 0.49, 0.47}, 0.2, 0.03, 0, 0, 0, -1, 0},
    {"pole_metal", Pattern::kMetal, {0.45, 0.46, 0.48}, {0.30, 0.31, 0.33}, 0.1, 0.01, 0, 0, 0, -1, 0},
    {"bin_green", Pattern::kUniform, {0.12, 0.35, 0.18}, {0.12, 0.35, 0.18}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"bollard_yellow", Pattern::kUniform, {0.88, 0.72, 0.08}, {0.88, 0.72, 0.08}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"car_white", Pattern::kUniform, {0.85, 0.86, 0.87}, {0.85, 0.86, 0.87}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"car_red", Pattern::kUniform, {0.60, 0.06, 0.06}, {0.60, 0.06, 0.06}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"car_dark", Pattern::kUniform, {0.10, 0.11, 0.13}, {0.10, 0.11, 0.13}, 0.0, 1.0, 0, 0, 0, 0.08, 0},
    {"cone_orange", Pattern::kUniform, {0.95, 0.35, 0.05}, {0.95, 0.35, 0.05}, 0.0, 1.0, 0, 0, 0, -1, 0},
    {"lamp_head", Pattern::kUniform, {0.95, 0.92, 0.85}, {0.95, 0.92, 0.85}, 0.0, 1.0, 0, 0, 0, -1, 60},
    {"pit_soil", Pattern::kSpeckle, {0.22, 0.16, 0.11}, {0.14, 0.10, 0.07}, 0.5, 0.01, 0, 0, 0, -1, 0},
};

const std::map<std::string, Material>& library() {
  static const std::map<std::string, Material> lib = [] {
    std::map<std::string, Material> m;
    for (const Entry& e : kLibrary) {
      Material mat;
      mat.name = e.name;
      mat.pattern = e.pattern;
      mat.color = e.color;
      mat.color2 = e.color2;
      mat.contrast = e.contrast;
      mat.scale = e.scale;
      mat.reflectance = e.reflectance;
      mat.roughness = e.roughness;
      mat.wetness = e.wetness;
      mat.ir_albedo = e.ir_albedo;
      mat.emission = e.emission;
      m.emplace(mat.name, mat);
    }
    return m;
  }();
  return lib;
}

const std::pair<Pattern, const char*> kPatternNames[] = {
    {Pattern::kUniform, "uniform"}, {Pattern::kPlaster, "plaster"},
    {Pattern::kCarpet, "carpet"},   {Pattern::kSpeckle, "speckle"},
    {Pattern::kAsphalt, "asphalt"}, {Pattern::kTiles, "tiles"},
    {Pattern::kChecker, "checker"}, {Pattern::kBricks, "bricks"},
    {Pattern::kWood, "wood"},       {Pattern::kFabric, "fabric"},
    {Pattern::kMetal, "metal"},     {Pattern::kCardboard, "cardboard"},
    {Pattern::kGrass, "grass"},     {Pattern::kStripes, "stripes"},
    {Pattern::kFacade, "facade"},   {Pattern::kCeilingTiles, "ceiling_tiles"},
    {Pattern::kPrinted, "printed"},
};

}  // namespace

bool Material::repetitive() const {
  switch (pattern) {
    case Pattern::kTiles:
    case Pattern::kChecker:
    case Pattern::kBricks:
    case Pattern::kStripes:
    case Pattern::kFacade:
    case Pattern::kCeilingTiles: return contrast >= 0.03;
    default: return false;
  }
}

const Material& builtin_material(const std::string& name) {
  const auto& lib = library();
  const auto it = lib.find(name);
  if (it == lib.end()) throw std::out_of_range("unknown material '" + name + "'");
  return it->second;
}

bool has_builtin_material(const std::string& name) { return library().count(name) > 0; }

Pattern pattern_from_string(const std::string& name) {
  for (const auto& [p, n] : kPatternNames)
    if (name == n) return p;
  std::string all;
  for (const auto& [p, n] : kPatternNames) all += std::string(all.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown pattern '" + name + "' (one of: " + all + ")");
}

const char* to_string(Pattern pattern) {
  for (const auto& [p, n] : kPatternNames)
    if (p == pattern) return n;
  return "?";
}

}  // namespace ivoa::sim
