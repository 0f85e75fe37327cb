#include "ivoa/sim/scene_spec.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace ivoa::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Scene coordinates (element positions) lie within this many metres of the origin.
constexpr double kMaxCoordinateM = 1000;
// Element sizes, material scales: no furniture or texture is larger.
constexpr double kMaxSizeM = 100;
// Emitted radiance of a lamp or panel (the shipped lights: 50-120).
constexpr double kMaxEmission = 10000;

std::string number_text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// A YAML node that knows where it is (file and key path) so every error
// names both.
class Reader {
 public:
  Reader(YAML::Node node, std::string path, const std::string& file)
      : node_(std::move(node)), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& what) const {
    std::string where = file_;
    if (node_ && node_.Mark().line >= 0) where += ":" + std::to_string(node_.Mark().line + 1);
    throw SceneSpecError(where + ": " + (path_.empty() ? std::string("(top level)") : path_) + ": " + what);
  }
  bool has(const std::string& key) const { return node_.IsMap() && node_[key]; }
  Reader operator[](const std::string& key) const {
    if (!node_.IsMap()) fail("expected a mapping");
    return Reader(node_[key], path_.empty() ? key : path_ + "." + key, file_);
  }
  Reader at(size_t i) const { return Reader(node_[i], path_ + "[" + std::to_string(i) + "]", file_); }
  size_t size() const {
    if (!node_.IsSequence()) fail("expected a list");
    return node_.size();
  }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_map() const { return node_.IsMap(); }
  const std::string& path() const { return path_; }

  // Every key is one of `keys`, a plain name, and given once (YAML would
  // silently keep the first of two).
  void allow(std::initializer_list<const char*> keys) const { allow(std::set<std::string>(keys.begin(), keys.end())); }
  void allow(const std::set<std::string>& ok) const {
    if (!node_.IsMap()) fail("expected a mapping");
    std::set<std::string> seen;
    for (const auto& kv : node_) {
      if (!kv.first.IsScalar()) Reader(kv.first, path_, file_).fail("a key must be a plain name");
      const std::string key = kv.first.Scalar();
      const std::string key_path = path_.empty() ? key : path_ + "." + key;
      if (!seen.insert(key).second) Reader(kv.first, key_path, file_).fail("given twice");
      if (!ok.count(key)) {
        std::string list;
        for (const auto& k : ok) list += (list.empty() ? "" : ", ") + k;
        Reader(kv.first, key_path, file_).fail("unknown key (expected one of: " + list + ")");
      }
    }
  }

  // NaN and infinities (.nan, .inf) would pass every range check below.
  double number() const {
    if (!node_.IsScalar()) fail("expected a number");
    double v = 0;
    try {
      v = node_.as<double>();
    } catch (const YAML::Exception&) {
      fail("expected a number, got '" + node_.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail("expected a finite number, got '" + node_.Scalar() + "'");
    return v;
  }
  // A number in [lo, hi].
  double number_in(double lo, double hi) const {
    const double v = number();
    if (v < lo || v > hi) fail("must be in [" + number_text(lo) + ", " + number_text(hi) + "], got " + number_text(v));
    return v;
  }
  double probability() const {
    const double p = number();
    if (!(p >= 0 && p <= 1)) fail("must be a probability in [0, 1]");
    return p;
  }
  bool boolean() const {
    try {
      return node_.as<bool>();
    } catch (const YAML::Exception&) {
      fail("expected true or false");
    }
  }
  std::string string() const {
    if (!node_.IsScalar()) fail("expected a string");
    return node_.Scalar();
  }
  std::vector<double> numbers(size_t n) const {
    if (!node_.IsSequence() || node_.size() != n) fail("expected a list of " + std::to_string(n) + " numbers");
    std::vector<double> out;
    for (size_t i = 0; i < n; ++i) out.push_back(at(i).number());
    return out;
  }
  // A number (fixed) or [min, max].
  Range range() const {
    if (node_.IsScalar()) return Range(number());
    const auto v = numbers(2);
    if (v[0] > v[1]) fail("range [min, max] has min > max");
    return Range(v[0], v[1]);
  }
  Eigen::Vector2d vec2() const {
    const auto v = numbers(2);
    return {v[0], v[1]};
  }
  // [x, y] in metres, within the scene's extent.
  Eigen::Vector2d position() const {
    const Eigen::Vector2d p = vec2();
    if (p.cwiseAbs().maxCoeff() > kMaxCoordinateM)
      fail("coordinates must lie within " + number_text(kMaxCoordinateM) + " m of the origin");
    return p;
  }
  std::vector<std::string> strings() const {
    if (node_.IsScalar()) return {string()};
    std::vector<std::string> out;
    for (size_t i = 0; i < size(); ++i) out.push_back(at(i).string());
    return out;
  }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& file_;
};

template <class T>
void maybe(const Reader& r, const char* key, T& out, T (Reader::*get)() const) {
  if (r.has(key)) out = (r[key].*get)();
}

Environment parse_environment(const Reader& r) {
  const std::string s = r.string();
  if (s == "indoor") return Environment::kIndoor;
  if (s == "outdoor") return Environment::kOutdoor;
  r.fail("expected indoor or outdoor, got '" + s + "'");
}

LayoutType parse_layout_type(const Reader& r) {
  const std::string s = r.string();
  if (s == "none") return LayoutType::kNone;
  if (s == "room") return LayoutType::kRoom;
  if (s == "corridor") return LayoutType::kCorridor;
  if (s == "office") return LayoutType::kOffice;
  if (s == "open") return LayoutType::kOpen;
  r.fail("expected one of none, room, corridor, office, open; got '" + s + "'");
}

Rgb parse_color(const Reader& r) {
  const auto v = r.numbers(3);
  for (double c : v)
    if (c < 0 || c > 1) r.fail("colour components must be in [0, 1] (sRGB)");
  return {v[0], v[1], v[2]};
}

Material parse_material(const Reader& r, const std::vector<Material>& earlier) {
  r.allow({"name", "base", "pattern", "color", "color2", "contrast", "scale", "reflectance", "roughness", "wetness",
           "ir_albedo", "emission"});
  if (!r.has("name")) r.fail("a material needs a name");
  Material m;
  if (r.has("base")) {
    const std::string base = r["base"].string();
    bool found = false;
    for (const Material& e : earlier)
      if (e.name == base) m = e, found = true;
    if (!found) {
      if (!has_builtin_material(base)) r["base"].fail("unknown material '" + base + "'");
      m = builtin_material(base);
    }
  }
  m.name = r["name"].string();
  if (r.has("pattern")) {
    try {
      m.pattern = pattern_from_string(r["pattern"].string());
    } catch (const std::invalid_argument& e) {
      r["pattern"].fail(e.what());
    }
  }
  if (r.has("color")) m.color = parse_color(r["color"]);
  if (r.has("color2")) m.color2 = parse_color(r["color2"]);
  if (r.has("contrast")) m.contrast = r["contrast"].number_in(0, 1);
  if (r.has("scale")) m.scale = r["scale"].number_in(1e-4, kMaxSizeM);
  if (r.has("reflectance")) m.reflectance = r["reflectance"].number_in(0, 1);
  if (r.has("roughness")) m.roughness = r["roughness"].number_in(0, M_PI / 2);
  if (r.has("wetness")) m.wetness = r["wetness"].number_in(0, 1);
  if (r.has("ir_albedo")) m.ir_albedo = r["ir_albedo"].number_in(-1, 1);
  if (r.has("emission")) m.emission = r["emission"].number_in(0, kMaxEmission);
  return m;
}

ElementSpec::Type parse_element_type(const Reader& r) {
  static const std::pair<const char*, ElementSpec::Type> kTypes[] = {
      {"box", ElementSpec::Type::kBox},
      {"cylinder", ElementSpec::Type::kCylinder},
      {"chair", ElementSpec::Type::kChair},
      {"table", ElementSpec::Type::kTable},
      {"wall", ElementSpec::Type::kWall},
      {"pole", ElementSpec::Type::kPole},
      {"lamp_post", ElementSpec::Type::kLampPost},
      {"curb", ElementSpec::Type::kCurb},
      {"floor_patch", ElementSpec::Type::kFloorPatch},
      {"puddle", ElementSpec::Type::kPuddle},
      {"pit", ElementSpec::Type::kPit},
      {"light", ElementSpec::Type::kLight},
  };
  const std::string s = r.string();
  for (const auto& [name, type] : kTypes)
    if (s == name) return type;
  std::string all;
  for (const auto& [name, type] : kTypes) all += std::string(all.empty() ? "" : ", ") + name;
  r.fail("unknown element type '" + s + "' (one of: " + all + ")");
}

// An element's size before its keys: the usual piece of furniture of its type.
Eigen::Vector3d default_size(ElementSpec::Type type) {
  using T = ElementSpec::Type;
  switch (type) {
    case T::kCylinder: return {0.4, 0.4, 0.8};
    case T::kChair: return {0.46, 0.46, 0.88};
    case T::kTable: return {1.2, 0.7, 0.73};
    case T::kWall: return {0, 0.12, 2.6};
    case T::kPole: return {0.08, 0.08, 2.5};
    case T::kLampPost: return {0.14, 0.14, 4.0};
    case T::kCurb: return {0, 0.15, 0.13};
    case T::kFloorPatch: return {1.5, 1.0, 0};
    case T::kPuddle: return {1.2, 0.8, 0};
    case T::kPit: return {0.6, 0.6, 0};
    case T::kLight: return {0.6, 0.6, 0};
    case T::kBox: break;
  }
  return ElementSpec{}.size;
}

// Walls and curbs run from one point to another; everything else stands at a position.
void parse_placement(const Reader& r, ElementSpec& e) {
  const bool linear = e.type == ElementSpec::Type::kWall || e.type == ElementSpec::Type::kCurb;
  if (linear) {
    if (!r.has("from") || !r.has("to")) r.fail(std::string(ElementSpec::type_name(e.type)) + " needs from and to");
    e.position = r["from"].position();
    e.end = r["to"].position();
    if ((e.end - e.position).norm() < 1e-3) r["to"].fail("from and to coincide");
  } else {
    if (!r.has("position")) r.fail(std::string(ElementSpec::type_name(e.type)) + " needs a position");
    e.position = r["position"].position();
  }
}

// `size` ([x, y] or [x, y, z]), then the single dimensions, which override it.
void parse_size(const Reader& r, Eigen::Vector3d& size) {
  if (r.has("size")) {
    const Reader s = r["size"];
    if (s.is_sequence() && s.size() == 2) {
      const auto v = s.numbers(2);
      size.x() = v[0];
      size.y() = v[1];
    } else {
      const auto v = s.numbers(3);
      size = {v[0], v[1], v[2]};
    }
  }
  if (r.has("diameter")) size.x() = size.y() = r["diameter"].number();
  if (r.has("height")) size.z() = r["height"].number();
  if (r.has("width")) size.y() = r["width"].number();
  if (r.has("thickness")) size.y() = r["thickness"].number();
  for (int i = 0; i < 3; ++i)
    if (size[i] < 0 || size[i] > kMaxSizeM) r.fail("sizes must be in [0, " + number_text(kMaxSizeM) + "] m");
}

std::vector<ElementSpec::Door> parse_doors(const Reader& d) {
  std::vector<ElementSpec::Door> doors;
  for (size_t i = 0; i < d.size(); ++i) {
    const Reader dr = d.at(i);
    dr.allow({"offset", "width", "height", "material", "open"});
    ElementSpec::Door door;
    if (dr.has("offset")) door.offset = dr["offset"].number_in(0, 2 * kMaxCoordinateM);
    if (dr.has("width")) door.width = dr["width"].number_in(0, kMaxSizeM);
    if (dr.has("height")) door.height = dr["height"].number_in(0, kMaxSizeM);
    maybe(dr, "material", door.material, &Reader::string);
    maybe(dr, "open", door.open, &Reader::boolean);
    doors.push_back(door);
  }
  return doors;
}

ElementSpec parse_element(const Reader& r) {
  r.allow({"type", "position", "from", "to", "size", "yaw_deg", "elevation", "depth", "intensity", "shape", "material",
           "height", "width", "thickness", "diameter", "baseboard", "doors"});
  if (!r.has("type")) r.fail("an element needs a type");
  ElementSpec e;
  e.type = parse_element_type(r["type"]);
  e.size = default_size(e.type);
  parse_placement(r, e);
  parse_size(r, e.size);
  if (r.has("yaw_deg")) e.yaw = r["yaw_deg"].number() * kDeg;
  if (r.has("elevation")) e.elevation = r["elevation"].number_in(0, kMaxSizeM);
  if (r.has("depth")) e.depth = r["depth"].number_in(0, kMaxSizeM);
  if (r.has("intensity")) e.intensity = r["intensity"].number_in(0, kMaxEmission);
  maybe(r, "material", e.material, &Reader::string);
  if (r.has("shape")) {
    e.shape = r["shape"].string();
    if (e.shape != "rect" && e.shape != "ellipse") r["shape"].fail("expected rect or ellipse");
  }
  if (r.has("baseboard")) {
    const Reader b = r["baseboard"];
    b.allow({"height", "material"});
    e.baseboard_height = b.has("height") ? b["height"].number_in(0, kMaxSizeM) : 0.1;
    e.baseboard_material = b.has("material") ? b["material"].string() : "baseboard_black";
  }
  if (r.has("doors")) e.doors = parse_doors(r["doors"]);
  return e;
}

std::string kind_list() {
  std::string list;
  for (const auto& k : obstacle_kinds()) list += (list.empty() ? "" : ", ") + k;
  return list;
}

// The kinds in name order, not the file's: a scene's draws do not depend on
// how its file lists them.
void parse_kinds(const Reader& r, std::vector<std::pair<std::string, double>>& kinds) {
  if (!r.is_map()) r.fail("expected a mapping of kind: weight");
  r.allow(obstacle_kinds());  // anything else is a typo
  kinds.clear();
  for (const auto& k : obstacle_kinds())
    if (r.has(k)) {
      const double w = r[k].number();
      if (w < 0) r[k].fail("weights must be >= 0");
      kinds.emplace_back(k, w);
    }
  if (kinds.empty()) r.fail("no kinds given (one of: " + kind_list() + ")");
}

void parse_layout(const Reader& r, LayoutSpec& out) {
  r.allow({"type", "width", "depth", "corridor_width", "corridor_length", "room_size", "ceiling_height",
           "door_probability", "facade_height"});
  if (r.has("type")) out.type = parse_layout_type(r["type"]);
  maybe(r, "width", out.width, &Reader::range);
  maybe(r, "depth", out.depth, &Reader::range);
  maybe(r, "corridor_width", out.corridor_width, &Reader::range);
  maybe(r, "corridor_length", out.corridor_length, &Reader::range);
  maybe(r, "room_size", out.room_size, &Reader::range);
  maybe(r, "ceiling_height", out.ceiling_height, &Reader::range);
  maybe(r, "door_probability", out.door_probability, &Reader::probability);
  maybe(r, "facade_height", out.facade_height, &Reader::range);
}

void parse_floor(const Reader& r, FloorSpec& out) {
  r.allow({"materials", "patch_count", "patch_materials", "patch_size"});
  maybe(r, "materials", out.materials, &Reader::strings);
  maybe(r, "patch_count", out.patch_count, &Reader::range);
  maybe(r, "patch_materials", out.patch_materials, &Reader::strings);
  maybe(r, "patch_size", out.patch_size, &Reader::range);
}

void parse_walls(const Reader& r, WallSpec& out) {
  r.allow({"materials", "baseboard_materials", "baseboard_height", "door_materials", "thickness"});
  maybe(r, "materials", out.materials, &Reader::strings);
  maybe(r, "baseboard_materials", out.baseboard_materials, &Reader::strings);
  maybe(r, "baseboard_height", out.baseboard_height, &Reader::range);
  maybe(r, "door_materials", out.door_materials, &Reader::strings);
  maybe(r, "thickness", out.thickness, &Reader::range);
}

void parse_obstacles(const Reader& r, ObstacleSpec& out) {
  r.allow({"count", "kinds", "materials", "color_jitter", "min_gap", "box_size", "box_height"});
  maybe(r, "count", out.count, &Reader::range);
  if (r.has("kinds")) parse_kinds(r["kinds"], out.kinds);
  maybe(r, "materials", out.materials, &Reader::strings);
  if (r.has("color_jitter")) out.color_jitter = r["color_jitter"].number_in(0, 1);
  if (r.has("min_gap")) out.min_gap = r["min_gap"].number_in(0, 50);
  maybe(r, "box_size", out.box_size, &Reader::range);
  maybe(r, "box_height", out.box_height, &Reader::range);
}

void parse_pits(const Reader& r, PitSpec& out) {
  r.allow({"probability", "count", "size", "depth"});
  maybe(r, "probability", out.probability, &Reader::probability);
  maybe(r, "count", out.count, &Reader::range);
  maybe(r, "size", out.size, &Reader::range);
  maybe(r, "depth", out.depth, &Reader::range);
}

void parse_lighting(const Reader& r, LightingSpec& out) {
  r.allow({"ambient", "light_spacing", "light_emission", "sun_elevation_deg", "sun_azimuth_deg", "sun_irradiance",
           "sky_irradiance", "overcast_probability", "low_light_factor", "night", "max_exposure_scale"});
  maybe(r, "ambient", out.ambient, &Reader::range);
  maybe(r, "light_spacing", out.light_spacing, &Reader::range);
  maybe(r, "light_emission", out.light_emission, &Reader::range);
  maybe(r, "sun_elevation_deg", out.sun_elevation_deg, &Reader::range);
  maybe(r, "sun_azimuth_deg", out.sun_azimuth_deg, &Reader::range);
  maybe(r, "sun_irradiance", out.sun_irradiance, &Reader::range);
  maybe(r, "sky_irradiance", out.sky_irradiance, &Reader::range);
  maybe(r, "overcast_probability", out.overcast_probability, &Reader::probability);
  maybe(r, "low_light_factor", out.low_light_factor, &Reader::range);
  maybe(r, "night", out.night, &Reader::boolean);
  if (r.has("max_exposure_scale")) out.max_exposure_scale = r["max_exposure_scale"].number_in(0.01, 100);
}

void parse_phenomena(const Reader& r, PhenomenaSpec& out) {
  r.allow({"reflective_floor", "wet_patches", "textureless_walls", "textureless_obstacles", "dark_stripes",
           "repetitive_floor", "glare", "low_light"});
  maybe(r, "reflective_floor", out.reflective_floor, &Reader::probability);
  maybe(r, "wet_patches", out.wet_patches, &Reader::range);
  maybe(r, "textureless_walls", out.textureless_walls, &Reader::probability);
  maybe(r, "textureless_obstacles", out.textureless_obstacles, &Reader::probability);
  maybe(r, "dark_stripes", out.dark_stripes, &Reader::probability);
  maybe(r, "repetitive_floor", out.repetitive_floor, &Reader::probability);
  maybe(r, "glare", out.glare, &Reader::probability);
  maybe(r, "low_light", out.low_light, &Reader::probability);
}

SceneSpec parse(const YAML::Node& root, const std::string& file) {
  const Reader r(root, "", file);
  if (!root.IsMap()) r.fail("a scene file is a mapping (name, environment, layout, ...)");
  r.allow({"name", "environment", "layout", "floor", "walls", "obstacles", "pits", "lighting", "phenomena", "materials",
           "material_jitter", "elements", "start"});
  SceneSpec s;
  s.source = file;
  maybe(r, "name", s.name, &Reader::string);
  if (r.has("environment")) s.environment = parse_environment(r["environment"]);
  if (s.environment == Environment::kOutdoor) {
    s.floor.materials = {"asphalt"};
    s.walls.materials = {"facade_windows", "facade_concrete"};
    s.walls.baseboard_materials = {};
    s.obstacles.materials = {"bin_green", "concrete_block"};
  }
  if (r.has("layout")) parse_layout(r["layout"], s.layout);
  if (r.has("floor")) parse_floor(r["floor"], s.floor);
  if (r.has("walls")) parse_walls(r["walls"], s.walls);
  if (r.has("obstacles")) parse_obstacles(r["obstacles"], s.obstacles);
  if (r.has("pits")) parse_pits(r["pits"], s.pits);
  if (r.has("lighting")) parse_lighting(r["lighting"], s.lighting);
  if (r.has("phenomena")) parse_phenomena(r["phenomena"], s.phenomena);
  if (r.has("material_jitter")) s.material_jitter = r["material_jitter"].number_in(0, 1);
  if (r.has("materials")) {
    const Reader m = r["materials"];
    for (size_t i = 0; i < m.size(); ++i) s.materials.push_back(parse_material(m.at(i), s.materials));
  }
  if (r.has("elements")) {
    const Reader e = r["elements"];
    for (size_t i = 0; i < e.size(); ++i) s.elements.push_back(parse_element(e.at(i)));
  }
  if (r.has("start")) {
    const auto v = r["start"].numbers(3);
    if (std::max(std::abs(v[0]), std::abs(v[1])) > kMaxCoordinateM)
      r["start"].fail("coordinates must lie within " + number_text(kMaxCoordinateM) + " m of the origin");
    s.start = Pose2D{v[0], v[1], v[2] * kDeg};
  }
  return s;
}

bool resolves(const SceneSpec& spec, const std::string& name) {
  for (const Material& m : spec.materials)
    if (m.name == name) return true;
  return has_builtin_material(name);
}

// A value that passed parsing but not validation: its key path
// ("floor.materials[1]") and what is wrong, for the caller to place.
struct InvalidKey {
  std::string key;
  std::string what;
};

void check_range(const std::string& key, const Range& r, double lo, double hi) {
  if (r.min > r.max || r.min < lo || r.max > hi)
    throw InvalidKey{key, "range [" + number_text(r.min) + ", " + number_text(r.max) + "] must lie in [" +
                              number_text(lo) + ", " + number_text(hi) + "] with min <= max"};
}

void check_material(const SceneSpec& spec, const std::string& key, const std::string& name) {
  if (!name.empty() && !resolves(spec, name)) throw InvalidKey{key, "unknown material '" + name + "'"};
}

void check_materials(const SceneSpec& spec, const std::string& key, const std::vector<std::string>& names,
                     bool may_be_empty = true) {
  if (names.empty() && !may_be_empty) throw InvalidKey{key, "needs at least one material"};
  for (size_t i = 0; i < names.size(); ++i) check_material(spec, key + "[" + std::to_string(i) + "]", names[i]);
}

void check_layout(const LayoutSpec& l) {
  check_range("layout.width", l.width, 1, 500);
  check_range("layout.depth", l.depth, 1, 500);
  check_range("layout.corridor_width", l.corridor_width, 1.0, 20);
  check_range("layout.corridor_length", l.corridor_length, 2, 500);
  check_range("layout.room_size", l.room_size, 2, 50);
  check_range("layout.ceiling_height", l.ceiling_height, 1.0, 20);
  check_range("layout.facade_height", l.facade_height, 0.5, 100);
}

void check_surfaces(const SceneSpec& spec) {
  check_materials(spec, "floor.materials", spec.floor.materials, false);
  check_materials(spec, "floor.patch_materials", spec.floor.patch_materials);
  check_range("floor.patch_count", spec.floor.patch_count, 0, 1000);
  check_range("floor.patch_size", spec.floor.patch_size, 0.05, 100);
  // Rooms, corridors and offices draw every wall from this list.
  const LayoutType walled[] = {LayoutType::kRoom, LayoutType::kCorridor, LayoutType::kOffice};
  const bool needs_walls = std::find(std::begin(walled), std::end(walled), spec.layout.type) != std::end(walled);
  if (needs_walls && spec.walls.materials.empty())
    throw InvalidKey{"walls.materials",
                     "needs at least one material: a room, corridor or office layout draws its "
                     "walls from it"};
  check_materials(spec, "walls.materials", spec.walls.materials);
  check_materials(spec, "walls.baseboard_materials", spec.walls.baseboard_materials);
  check_materials(spec, "walls.door_materials", spec.walls.door_materials);
  check_range("walls.baseboard_height", spec.walls.baseboard_height, 0, 1);
  check_range("walls.thickness", spec.walls.thickness, 0.02, 2);
}

void check_contents(const SceneSpec& spec) {
  for (const auto& [kind, weight] : spec.obstacles.kinds)
    if (!obstacle_kinds().count(kind))
      throw InvalidKey{"obstacles.kinds", "unknown kind '" + kind + "' (one of: " + kind_list() + ")"};
  check_materials(spec, "obstacles.materials", spec.obstacles.materials);
  check_range("obstacles.count", spec.obstacles.count, 0, 5000);
  check_range("obstacles.box_size", spec.obstacles.box_size, 0.02, 20);
  check_range("obstacles.box_height", spec.obstacles.box_height, 0.01, 20);
  if (spec.obstacles.count.max > 0 && spec.obstacles.materials.empty())
    throw InvalidKey{"obstacles.materials", "needs at least one material"};
  check_range("pits.count", spec.pits.count, 0, 100);
  check_range("pits.size", spec.pits.size, 0.05, 20);
  check_range("pits.depth", spec.pits.depth, 0.02, 20);
  check_range("phenomena.wet_patches", spec.phenomena.wet_patches, 0, 1000);
  check_range("material_jitter", Range(spec.material_jitter), 0, 1);
}

void check_lighting(const LightingSpec& l) {
  check_range("lighting.ambient", l.ambient, 0, 10);
  check_range("lighting.sun_elevation_deg", l.sun_elevation_deg, 1, 90);
  check_range("lighting.low_light_factor", l.low_light_factor, 1e-4, 1);
  check_range("lighting.light_spacing", l.light_spacing, 0.5, 50);
  check_range("lighting.light_emission", l.light_emission, 0, kMaxEmission);
  check_range("lighting.sun_azimuth_deg", l.sun_azimuth_deg, -360, 360);
  check_range("lighting.sun_irradiance", l.sun_irradiance, 0, 1e5);
  check_range("lighting.sky_irradiance", l.sky_irradiance, 0, 1e5);
}

void check_elements(const SceneSpec& spec) {
  for (size_t i = 0; i < spec.elements.size(); ++i) {
    const ElementSpec& e = spec.elements[i];
    const std::string key = "elements[" + std::to_string(i) + "]";
    check_material(spec, key + ".material", e.material);
    check_material(spec, key + ".baseboard.material", e.baseboard_material);
    for (size_t j = 0; j < e.doors.size(); ++j)
      check_material(spec, key + ".doors[" + std::to_string(j) + "].material", e.doors[j].material);
  }
}

// Throws InvalidKey for the first value out of place.
void check_spec(const SceneSpec& spec) {
  check_layout(spec.layout);
  check_surfaces(spec);
  check_contents(spec);
  check_lighting(spec.lighting);
  check_elements(spec);
}

// ":12" for the line of `key` ("a.b[2].c") in `root`, as deep as the path
// goes in the file; "" if not even its first part is there.
std::string line_of(const YAML::Node& root, const std::string& key) {
  std::vector<YAML::Node> path{root};
  std::istringstream parts(key);
  std::string part;
  while (std::getline(parts, part, '.')) {
    const size_t bracket = part.find('[');
    const YAML::Node parent = path.back();
    if (!parent.IsMap()) break;
    const YAML::Node node = parent[part.substr(0, bracket)];
    if (!node) break;
    path.push_back(node);
    if (bracket == std::string::npos) continue;
    const size_t index = std::stoul(part.substr(bracket + 1));
    if (!node.IsSequence() || index >= node.size()) break;
    path.push_back(node[index]);
  }
  if (path.size() == 1 || path.back().Mark().line < 0) return "";
  return ":" + std::to_string(path.back().Mark().line + 1);
}

}  // namespace

const std::set<std::string>& obstacle_kinds() {
  static const std::set<std::string> kinds = {"bench", "bin",      "bollard",   "box",     "cabinet", "car",  "chair",
                                              "curb",  "cylinder", "lamp_post", "planter", "pole",    "table"};
  return kinds;
}

const char* ElementSpec::type_name(Type type) {
  switch (type) {
    case Type::kBox: return "box";
    case Type::kCylinder: return "cylinder";
    case Type::kChair: return "chair";
    case Type::kTable: return "table";
    case Type::kWall: return "wall";
    case Type::kPole: return "pole";
    case Type::kLampPost: return "lamp_post";
    case Type::kCurb: return "curb";
    case Type::kFloorPatch: return "floor_patch";
    case Type::kPuddle: return "puddle";
    case Type::kPit: return "pit";
    case Type::kLight: return "light";
  }
  return "?";
}

void validate(const SceneSpec& spec) {
  try {
    check_spec(spec);
  } catch (const InvalidKey& e) {
    throw SceneSpecError(spec.source + ": " + e.key + ": " + e.what);
  }
}

SceneSpec parse_scene_spec(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw SceneSpecError(source_name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  SceneSpec spec = parse(root, source_name);
  try {
    check_spec(spec);
  } catch (const InvalidKey& e) {
    throw SceneSpecError(source_name + line_of(root, e.key) + ": " + e.key + ": " + e.what);
  }
  return spec;
}

SceneSpec load_scene_spec(const std::string& yaml_path) {
  std::ifstream in(yaml_path);
  if (!in) throw SceneSpecError(yaml_path + ": cannot open scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_scene_spec(text.str(), yaml_path);
}

SceneSpec make_bare_spec(Environment environment, const std::string& floor_material) {
  SceneSpec s;
  s.name = "bare";
  s.environment = environment;
  s.layout.type = LayoutType::kNone;
  s.floor.materials = {floor_material};
  s.obstacles.count = Range(0);
  s.pits.probability = 0;
  s.phenomena = PhenomenaSpec{0, Range(0), 0, 0, 0, 0, 0, 0};
  s.lighting.ambient = Range(0.5);
  s.lighting.light_emission = Range(80);
  s.lighting.light_spacing = Range(3.0);
  s.lighting.sun_elevation_deg = Range(45);
  s.lighting.sun_azimuth_deg = Range(200);
  s.lighting.sun_irradiance = Range(300);
  s.lighting.sky_irradiance = Range(60);
  s.lighting.overcast_probability = 0;
  s.layout.ceiling_height = Range(2.8);
  s.start = Pose2D{0, 0, 0};
  return s;
}

}  // namespace ivoa::sim
