#include "ivoa/sim/scene_spec.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace ivoa::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

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

  void allow(std::initializer_list<const char*> keys) const {
    if (!node_.IsMap()) fail("expected a mapping");
    std::set<std::string> ok(keys.begin(), keys.end());
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (!ok.count(key)) {
        std::string list;
        for (const auto& k : ok) list += (list.empty() ? "" : ", ") + k;
        Reader(kv.first, path_.empty() ? key : path_ + "." + key, file_).fail("unknown key (expected one of: " + list + ")");
      }
    }
  }

  double number() const {
    if (!node_.IsScalar()) fail("expected a number");
    try {
      return node_.as<double>();
    } catch (const YAML::Exception&) {
      fail("expected a number, got '" + node_.Scalar() + "'");
    }
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
  maybe(r, "contrast", m.contrast, &Reader::number);
  maybe(r, "scale", m.scale, &Reader::number);
  maybe(r, "reflectance", m.reflectance, &Reader::number);
  maybe(r, "roughness", m.roughness, &Reader::number);
  maybe(r, "wetness", m.wetness, &Reader::number);
  maybe(r, "ir_albedo", m.ir_albedo, &Reader::number);
  maybe(r, "emission", m.emission, &Reader::number);
  if (m.scale <= 0) r["scale"].fail("must be > 0");
  if (m.contrast < 0 || m.contrast > 1) r["contrast"].fail("must be in [0, 1]");
  if (m.reflectance < 0 || m.reflectance > 1) r["reflectance"].fail("must be in [0, 1]");
  return m;
}

ElementSpec::Type parse_element_type(const Reader& r) {
  static const std::pair<const char*, ElementSpec::Type> kTypes[] = {
      {"box", ElementSpec::Type::kBox},         {"cylinder", ElementSpec::Type::kCylinder},
      {"chair", ElementSpec::Type::kChair},     {"table", ElementSpec::Type::kTable},
      {"wall", ElementSpec::Type::kWall},       {"pole", ElementSpec::Type::kPole},
      {"lamp_post", ElementSpec::Type::kLampPost}, {"curb", ElementSpec::Type::kCurb},
      {"floor_patch", ElementSpec::Type::kFloorPatch}, {"puddle", ElementSpec::Type::kPuddle},
      {"pit", ElementSpec::Type::kPit},         {"light", ElementSpec::Type::kLight},
  };
  const std::string s = r.string();
  for (const auto& [name, type] : kTypes)
    if (s == name) return type;
  std::string all;
  for (const auto& [name, type] : kTypes) all += std::string(all.empty() ? "" : ", ") + name;
  r.fail("unknown element type '" + s + "' (one of: " + all + ")");
}

ElementSpec parse_element(const Reader& r) {
  r.allow({"type", "position", "from", "to", "size", "yaw_deg", "elevation", "depth", "intensity", "shape", "material",
           "height", "width", "thickness", "diameter", "baseboard", "doors"});
  if (!r.has("type")) r.fail("an element needs a type");
  ElementSpec e;
  e.type = parse_element_type(r["type"]);
  using T = ElementSpec::Type;
  const bool linear = e.type == T::kWall || e.type == T::kCurb;
  // Defaults per type, then the keys given.
  switch (e.type) {
    case T::kCylinder: e.size = {0.4, 0.4, 0.8}; break;
    case T::kChair: e.size = {0.46, 0.46, 0.88}; break;
    case T::kTable: e.size = {1.2, 0.7, 0.73}; break;
    case T::kWall: e.size = {0, 0.12, 2.6}; break;
    case T::kPole: e.size = {0.08, 0.08, 2.5}; break;
    case T::kLampPost: e.size = {0.14, 0.14, 4.0}; break;
    case T::kCurb: e.size = {0, 0.15, 0.13}; break;
    case T::kFloorPatch: e.size = {1.5, 1.0, 0}; break;
    case T::kPuddle: e.size = {1.2, 0.8, 0}; break;
    case T::kPit: e.size = {0.6, 0.6, 0}; break;
    case T::kLight: e.size = {0.6, 0.6, 0}; break;
    case T::kBox: break;
  }
  if (linear) {
    if (!r.has("from") || !r.has("to")) r.fail(std::string(ElementSpec::type_name(e.type)) + " needs from and to");
    e.position = r["from"].vec2();
    e.end = r["to"].vec2();
    if ((e.end - e.position).norm() < 1e-3) r["to"].fail("from and to coincide");
  } else {
    if (!r.has("position")) r.fail(std::string(ElementSpec::type_name(e.type)) + " needs a position");
    e.position = r["position"].vec2();
  }
  if (r.has("size")) {
    const Reader s = r["size"];
    if (s.is_sequence() && s.size() == 2) {
      const auto v = s.numbers(2);
      e.size.x() = v[0];
      e.size.y() = v[1];
    } else {
      const auto v = s.numbers(3);
      e.size = {v[0], v[1], v[2]};
    }
  }
  if (r.has("diameter")) e.size.x() = e.size.y() = r["diameter"].number();
  if (r.has("height")) e.size.z() = r["height"].number();
  if (r.has("width")) e.size.y() = r["width"].number();
  if (r.has("thickness")) e.size.y() = r["thickness"].number();
  if (r.has("yaw_deg")) e.yaw = r["yaw_deg"].number() * kDeg;
  maybe(r, "elevation", e.elevation, &Reader::number);
  maybe(r, "depth", e.depth, &Reader::number);
  maybe(r, "intensity", e.intensity, &Reader::number);
  maybe(r, "material", e.material, &Reader::string);
  if (r.has("shape")) {
    e.shape = r["shape"].string();
    if (e.shape != "rect" && e.shape != "ellipse") r["shape"].fail("expected rect or ellipse");
  }
  if (r.has("baseboard")) {
    const Reader b = r["baseboard"];
    b.allow({"height", "material"});
    e.baseboard_height = b.has("height") ? b["height"].number() : 0.1;
    e.baseboard_material = b.has("material") ? b["material"].string() : "baseboard_black";
  }
  if (r.has("doors")) {
    const Reader d = r["doors"];
    for (size_t i = 0; i < d.size(); ++i) {
      const Reader dr = d.at(i);
      dr.allow({"offset", "width", "height", "material", "open"});
      ElementSpec::Door door;
      maybe(dr, "offset", door.offset, &Reader::number);
      maybe(dr, "width", door.width, &Reader::number);
      maybe(dr, "height", door.height, &Reader::number);
      maybe(dr, "material", door.material, &Reader::string);
      maybe(dr, "open", door.open, &Reader::boolean);
      e.doors.push_back(door);
    }
  }
  for (int i = 0; i < 3; ++i)
    if (e.size[i] < 0) r["size"].fail("sizes must be >= 0");
  return e;
}

void parse_kinds(const Reader& r, std::vector<std::pair<std::string, double>>& kinds) {
  static const std::set<std::string> kKnown = {"box",   "cylinder", "chair", "table", "bin",       "pole", "bollard",
                                               "bench", "planter",  "car",   "cabinet", "lamp_post", "curb"};
  if (!r.is_map()) r.fail("expected a mapping of kind: weight");
  kinds.clear();
  // Iterate through the reader's keys via allow() + lookups.
  std::string list;
  for (const auto& k : kKnown) list += (list.empty() ? "" : ", ") + k;
  for (const auto& k : kKnown)
    if (r.has(k)) {
      const double w = r[k].number();
      if (w < 0) r[k].fail("weights must be >= 0");
      kinds.emplace_back(k, w);
    }
  // Anything else is a typo.
  r.allow({"box", "cylinder", "chair", "table", "bin", "pole", "bollard", "bench", "planter", "car", "cabinet",
           "lamp_post", "curb"});
  if (kinds.empty()) r.fail("no kinds given (one of: " + list + ")");
}

SceneSpec parse(const YAML::Node& root, const std::string& file) {
  const Reader r(root, "", file);
  if (!root.IsMap()) r.fail("a scene file is a mapping (name, environment, layout, ...)");
  r.allow({"name", "environment", "layout", "floor", "walls", "obstacles", "pits", "lighting", "phenomena", "materials",
           "elements", "start"});
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
  if (r.has("layout")) {
    const Reader l = r["layout"];
    l.allow({"type", "width", "depth", "corridor_width", "corridor_length", "room_size", "ceiling_height",
             "door_probability", "facade_height"});
    if (l.has("type")) s.layout.type = parse_layout_type(l["type"]);
    maybe(l, "width", s.layout.width, &Reader::range);
    maybe(l, "depth", s.layout.depth, &Reader::range);
    maybe(l, "corridor_width", s.layout.corridor_width, &Reader::range);
    maybe(l, "corridor_length", s.layout.corridor_length, &Reader::range);
    maybe(l, "room_size", s.layout.room_size, &Reader::range);
    maybe(l, "ceiling_height", s.layout.ceiling_height, &Reader::range);
    maybe(l, "door_probability", s.layout.door_probability, &Reader::probability);
    maybe(l, "facade_height", s.layout.facade_height, &Reader::range);
  }
  if (r.has("floor")) {
    const Reader f = r["floor"];
    f.allow({"materials", "patch_count", "patch_materials", "patch_size"});
    maybe(f, "materials", s.floor.materials, &Reader::strings);
    maybe(f, "patch_count", s.floor.patch_count, &Reader::range);
    maybe(f, "patch_materials", s.floor.patch_materials, &Reader::strings);
    maybe(f, "patch_size", s.floor.patch_size, &Reader::range);
  }
  if (r.has("walls")) {
    const Reader w = r["walls"];
    w.allow({"materials", "baseboard_materials", "baseboard_height", "door_materials", "thickness"});
    maybe(w, "materials", s.walls.materials, &Reader::strings);
    maybe(w, "baseboard_materials", s.walls.baseboard_materials, &Reader::strings);
    maybe(w, "baseboard_height", s.walls.baseboard_height, &Reader::range);
    maybe(w, "door_materials", s.walls.door_materials, &Reader::strings);
    maybe(w, "thickness", s.walls.thickness, &Reader::range);
  }
  if (r.has("obstacles")) {
    const Reader o = r["obstacles"];
    o.allow({"count", "kinds", "materials", "color_jitter", "min_gap", "box_size", "box_height"});
    maybe(o, "count", s.obstacles.count, &Reader::range);
    if (o.has("kinds")) parse_kinds(o["kinds"], s.obstacles.kinds);
    maybe(o, "materials", s.obstacles.materials, &Reader::strings);
    maybe(o, "color_jitter", s.obstacles.color_jitter, &Reader::number);
    maybe(o, "min_gap", s.obstacles.min_gap, &Reader::number);
    maybe(o, "box_size", s.obstacles.box_size, &Reader::range);
    maybe(o, "box_height", s.obstacles.box_height, &Reader::range);
  }
  if (r.has("pits")) {
    const Reader p = r["pits"];
    p.allow({"probability", "count", "size", "depth"});
    maybe(p, "probability", s.pits.probability, &Reader::probability);
    maybe(p, "count", s.pits.count, &Reader::range);
    maybe(p, "size", s.pits.size, &Reader::range);
    maybe(p, "depth", s.pits.depth, &Reader::range);
  }
  if (r.has("lighting")) {
    const Reader l = r["lighting"];
    l.allow({"ambient", "light_spacing", "light_emission", "sun_elevation_deg", "sun_azimuth_deg", "sun_irradiance",
             "sky_irradiance", "overcast_probability", "low_light_factor", "night", "max_exposure_scale"});
    maybe(l, "ambient", s.lighting.ambient, &Reader::range);
    maybe(l, "light_spacing", s.lighting.light_spacing, &Reader::range);
    maybe(l, "light_emission", s.lighting.light_emission, &Reader::range);
    maybe(l, "sun_elevation_deg", s.lighting.sun_elevation_deg, &Reader::range);
    maybe(l, "sun_azimuth_deg", s.lighting.sun_azimuth_deg, &Reader::range);
    maybe(l, "sun_irradiance", s.lighting.sun_irradiance, &Reader::range);
    maybe(l, "sky_irradiance", s.lighting.sky_irradiance, &Reader::range);
    maybe(l, "overcast_probability", s.lighting.overcast_probability, &Reader::probability);
    maybe(l, "low_light_factor", s.lighting.low_light_factor, &Reader::range);
    maybe(l, "night", s.lighting.night, &Reader::boolean);
    maybe(l, "max_exposure_scale", s.lighting.max_exposure_scale, &Reader::number);
  }
  if (r.has("phenomena")) {
    const Reader p = r["phenomena"];
    p.allow({"reflective_floor", "wet_patches", "textureless_walls", "textureless_obstacles", "dark_stripes",
             "repetitive_floor", "glare", "low_light"});
    maybe(p, "reflective_floor", s.phenomena.reflective_floor, &Reader::probability);
    maybe(p, "wet_patches", s.phenomena.wet_patches, &Reader::range);
    maybe(p, "textureless_walls", s.phenomena.textureless_walls, &Reader::probability);
    maybe(p, "textureless_obstacles", s.phenomena.textureless_obstacles, &Reader::probability);
    maybe(p, "dark_stripes", s.phenomena.dark_stripes, &Reader::probability);
    maybe(p, "repetitive_floor", s.phenomena.repetitive_floor, &Reader::probability);
    maybe(p, "glare", s.phenomena.glare, &Reader::probability);
    maybe(p, "low_light", s.phenomena.low_light, &Reader::probability);
  }
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
    s.start = Pose2D{v[0], v[1], v[2] * kDeg};
  }
  return s;
}

bool resolves(const SceneSpec& spec, const std::string& name) {
  for (const Material& m : spec.materials)
    if (m.name == name) return true;
  return has_builtin_material(name);
}

void check_range(const SceneSpec& spec, const std::string& key, const Range& r, double lo, double hi) {
  if (r.min > r.max || r.min < lo || r.max > hi)
    throw SceneSpecError(spec.source + ": " + key + ": range [" + std::to_string(r.min) + ", " +
                         std::to_string(r.max) + "] must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                         "] with min <= max");
}

void check_materials(const SceneSpec& spec, const std::string& key, const std::vector<std::string>& names,
                     bool may_be_empty = true) {
  if (names.empty() && !may_be_empty) throw SceneSpecError(spec.source + ": " + key + ": needs at least one material");
  for (const auto& n : names)
    if (!resolves(spec, n)) throw SceneSpecError(spec.source + ": " + key + ": unknown material '" + n + "'");
}

}  // namespace

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
  const auto& l = spec.layout;
  check_range(spec, "layout.width", l.width, 1, 500);
  check_range(spec, "layout.depth", l.depth, 1, 500);
  check_range(spec, "layout.corridor_width", l.corridor_width, 1.0, 20);
  check_range(spec, "layout.corridor_length", l.corridor_length, 2, 500);
  check_range(spec, "layout.room_size", l.room_size, 2, 50);
  check_range(spec, "layout.ceiling_height", l.ceiling_height, 1.0, 20);
  check_range(spec, "layout.facade_height", l.facade_height, 0.5, 100);
  check_materials(spec, "floor.materials", spec.floor.materials, false);
  check_materials(spec, "floor.patch_materials", spec.floor.patch_materials);
  check_range(spec, "floor.patch_count", spec.floor.patch_count, 0, 1000);
  check_range(spec, "floor.patch_size", spec.floor.patch_size, 0.05, 100);
  check_materials(spec, "walls.materials", spec.walls.materials);
  check_materials(spec, "walls.baseboard_materials", spec.walls.baseboard_materials);
  check_materials(spec, "walls.door_materials", spec.walls.door_materials);
  check_range(spec, "walls.baseboard_height", spec.walls.baseboard_height, 0, 1);
  check_range(spec, "walls.thickness", spec.walls.thickness, 0.02, 2);
  check_materials(spec, "obstacles.materials", spec.obstacles.materials);
  check_range(spec, "obstacles.count", spec.obstacles.count, 0, 5000);
  check_range(spec, "obstacles.box_size", spec.obstacles.box_size, 0.02, 20);
  check_range(spec, "obstacles.box_height", spec.obstacles.box_height, 0.01, 20);
  if (spec.obstacles.count.max > 0 && spec.obstacles.materials.empty())
    throw SceneSpecError(spec.source + ": obstacles.materials: needs at least one material");
  check_range(spec, "pits.count", spec.pits.count, 0, 100);
  check_range(spec, "pits.size", spec.pits.size, 0.05, 20);
  check_range(spec, "pits.depth", spec.pits.depth, 0.02, 20);
  check_range(spec, "lighting.sun_elevation_deg", spec.lighting.sun_elevation_deg, 1, 90);
  check_range(spec, "lighting.low_light_factor", spec.lighting.low_light_factor, 1e-4, 1);
  check_range(spec, "lighting.light_spacing", spec.lighting.light_spacing, 0.5, 50);
  check_range(spec, "phenomena.wet_patches", spec.phenomena.wet_patches, 0, 1000);
  for (size_t i = 0; i < spec.elements.size(); ++i) {
    const ElementSpec& e = spec.elements[i];
    const std::string key = "elements[" + std::to_string(i) + "]";
    if (!e.material.empty() && !resolves(spec, e.material))
      throw SceneSpecError(spec.source + ": " + key + ".material: unknown material '" + e.material + "'");
    if (!e.baseboard_material.empty() && !resolves(spec, e.baseboard_material))
      throw SceneSpecError(spec.source + ": " + key + ".baseboard.material: unknown material '" +
                           e.baseboard_material + "'");
    for (const auto& d : e.doors)
      if (!d.material.empty() && !resolves(spec, d.material))
        throw SceneSpecError(spec.source + ": " + key + ".doors.material: unknown material '" + d.material + "'");
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
  validate(spec);
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
