#include "scene_builder.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>

#include "geometry.hpp"
#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::sim::detail {
namespace {

using GT = sim_ground_truth_t;

// Linear luminance (of the texture's mean) under which a baseboard shows
// as a dark stripe.
constexpr float kDarkStripeLuminance = 0.02f;

// Textures depend only on the material (not on the scene), so every scene in
// a process shares them: the library's maps are synthesised once.
std::shared_ptr<const Texture> cached_texture(const Material& m) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Texture>> cache;
  std::ostringstream key;
  key.precision(9);
  key << m.name << '|' << static_cast<int>(m.pattern) << '|' << m.color[0] << ',' << m.color[1] << ',' << m.color[2]
      << '|' << m.color2[0] << ',' << m.color2[1] << ',' << m.color2[2] << '|' << m.contrast << '|' << m.scale;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[key.str()];
  if (!slot) slot = std::make_shared<Texture>(synthesize_texture(m, hash_string(key.str().c_str())));
  return slot;
}

// Smooth random field for puddle outlines.
float lattice_noise(const std::vector<float>& lattice, int n, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double tx = x - x0, ty = y - y0;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  auto v = [&](int i, int j) {
    return lattice[static_cast<size_t>(((j % n) + n) % n) * n + static_cast<size_t>(((i % n) + n) % n)];
  };
  const double a = v(x0, y0) + (v(x0 + 1, y0) - v(x0, y0)) * sx;
  const double b = v(x0, y0 + 1) + (v(x0 + 1, y0 + 1) - v(x0, y0 + 1)) * sx;
  return static_cast<float>(a + (b - a) * sy);
}

}  // namespace

MaterialData make_material_data(const Material& m) {
  MaterialData d;
  d.spec = m;
  d.texture = cached_texture(m);
  const Rgbf lin = to_linear(m.color);
  d.emission = lin * static_cast<float>(m.emission);
  d.f0 = static_cast<float>(m.reflectance);
  d.roughness = static_cast<float>(m.roughness);
  d.diffuse_scale = static_cast<float>(1.0 - 0.55 * m.wetness);
  const float lum = d.texture->mean().luminance() * d.diffuse_scale;
  d.ir_albedo = m.ir_albedo >= 0 ? static_cast<float>(m.ir_albedo) : std::min(1.0f, 0.15f + std::sqrt(lum));
  if (m.textureless()) d.phenomena |= GT::PHENOMENON_TEXTURELESS;
  if (m.repetitive()) d.phenomena |= GT::PHENOMENON_REPETITIVE;
  if (lum < kDarkStripeLuminance) d.phenomena |= GT::PHENOMENON_DARK_STRIPE;  // only used where it is a baseboard
  return d;
}

SceneBuilder::SceneBuilder(const SceneSpec& spec, uint64_t seed)
    : spec_(spec), rng_(hash_combine(seed, hash_string(spec.name.c_str()))), data_(std::make_shared<SceneData>()) {
  data_->name = spec.name;
  data_->seed = seed;
  data_->environment = spec.environment;
  data_->max_exposure_scale = static_cast<float>(spec.lighting.max_exposure_scale);
  data_->has_ceiling = spec.environment == Environment::kIndoor;
  data_->ceiling_height =
      static_cast<float>(rng_.uniform(spec.layout.ceiling_height.min, spec.layout.ceiling_height.max));
}

const Material& SceneBuilder::resolve(const std::string& name) const {
  for (const Material& m : spec_.materials)
    if (m.name == name) return m;
  if (!has_builtin_material(name)) throw SceneSpecError(spec_.source + ": unknown material '" + name + "'");
  return builtin_material(name);
}

uint16_t SceneBuilder::material(const std::string& name) {
  auto& mats = data_->materials;
  for (size_t i = 0; i < mats.size(); ++i)
    if (mats[i].spec.name == name) return static_cast<uint16_t>(i);
  mats.push_back(make_material_data(as_this_seed_shows(resolve(name))));
  return static_cast<uint16_t>(mats.size() - 1);
}

Material SceneBuilder::as_this_seed_shows(Material m) const {
  const double j = spec_.material_jitter;
  if (j <= 0 || m.emission > 0) return m;
  // A wet variant ("paving_wet") draws as its dry material does, so a wet
  // patch differs from the floor around it by its water film only.
  std::string family = m.name;
  if (family.size() > 4 && family.compare(family.size() - 4, 4, "_wet") == 0) family.resize(family.size() - 4);
  Rng rng(hash_combine(data_->seed, hash_string(("material_jitter/" + spec_.name + "/" + family).c_str())));
  // A dark material only darkens: lighter, a baseboard would stop being the
  // dark stripe the scene file asked for. Judged by its main colour, the
  // lighter of every shipped baseboard's two.
  const bool dark = to_linear(m.color).luminance() < kDarkStripeLuminance;
  const double brightness = std::exp(0.5 * j * rng.uniform(-1, 1));
  Rgb gain;
  for (double& g : gain) {
    g = brightness * std::exp(0.15 * j * rng.uniform(-1, 1));
    if (dark) g = std::min(g, 1.0);
  }
  for (int c = 0; c < 3; ++c) {
    m.color[c] = std::clamp(m.color[c] * gain[c], 0.0, 1.0);
    m.color2[c] = std::clamp(m.color2[c] * gain[c], 0.0, 1.0);
  }
  // Kept above textureless()'s and repetitive()'s 0.03, so the phenomena stay.
  const double contrast = m.contrast * std::exp(j * rng.uniform(-1, 1));
  if (!m.textureless()) m.contrast = std::clamp(contrast, 0.05, 1.0);
  m.scale *= std::exp(j * rng.uniform(-1, 1));
  return m;
}

std::string SceneBuilder::pick(const std::vector<std::string>& palette,
                               const std::function<bool(const Material&)>& has_property, double p) {
  // validate() keeps every palette the builder draws from non-empty.
  if (palette.empty()) throw std::logic_error("SceneBuilder::pick: no material to draw from");
  std::vector<std::string> with, without;
  for (const auto& n : palette) (has_property(resolve(n)) ? with : without).push_back(n);
  const bool want = rng_.chance(p);
  const auto& pool = want ? (with.empty() ? palette : with) : (without.empty() ? palette : without);
  return pool[static_cast<size_t>(rng_.uniform_int(0, static_cast<int>(pool.size()) - 1))];
}

std::string SceneBuilder::pick_floor(const std::vector<std::string>& palette) {
  const auto& ph = spec_.phenomena;
  const double r = rng_.uniform();
  if (r < ph.reflective_floor)
    return pick(
        palette, [](const Material& m) { return m.reflective(); }, 1.0);
  if (r < ph.reflective_floor + ph.repetitive_floor)
    return pick(
        palette, [](const Material& m) { return m.repetitive() && !m.reflective(); }, 1.0);
  return pick(
      palette, [](const Material& m) { return !m.repetitive() && !m.reflective(); }, 1.0);
}

std::string SceneBuilder::pick_wall(const std::vector<std::string>& palette) {
  return pick(
      palette, [](const Material& m) { return m.textureless(); }, spec_.phenomena.textureless_walls);
}

std::string SceneBuilder::pick_obstacle(const std::vector<std::string>& palette) {
  return pick(
      palette, [](const Material& m) { return m.textureless(); }, spec_.phenomena.textureless_obstacles);
}

Prism& SceneBuilder::add_rect(double cx, double cy, double length, double width, double yaw, double z0, double z1,
                              uint16_t mat, uint8_t surface) {
  Prism p;
  p.shape = Prism::kRect;
  p.surface = surface;
  p.cx = static_cast<float>(cx);
  p.cy = static_cast<float>(cy);
  p.hx = static_cast<float>(std::max(0.005, length / 2));
  p.hy = static_cast<float>(std::max(0.005, width / 2));
  p.cos_yaw = static_cast<float>(std::cos(yaw));
  p.sin_yaw = static_cast<float>(std::sin(yaw));
  p.z0 = static_cast<float>(z0);
  p.z1 = static_cast<float>(z1);
  p.material = p.top_material = p.base_material = mat;
  p.u_offset = static_cast<float>(rng_.uniform(0, 10));
  p.v_offset = static_cast<float>(rng_.uniform(0, 10));
  data_->prisms.push_back(p);
  return data_->prisms.back();
}

Prism& SceneBuilder::add_circle(double cx, double cy, double radius, double z0, double z1, uint16_t mat,
                                uint8_t surface) {
  Prism& p = add_rect(cx, cy, 2 * radius, 2 * radius, 0, z0, z1, mat, surface);
  p.shape = Prism::kCircle;
  p.hx = p.hy = static_cast<float>(radius);
  return p;
}

namespace {
Rgbf jitter_tint(Rng& rng, double amount) {
  if (amount <= 0) return {1, 1, 1};
  const double shade = 1.0 + rng.uniform(-amount, amount);
  const float r = static_cast<float>(shade * (1.0 + rng.uniform(-amount, amount) * 0.5));
  const float g = static_cast<float>(shade * (1.0 + rng.uniform(-amount, amount) * 0.5));
  const float b = static_cast<float>(shade * (1.0 + rng.uniform(-amount, amount) * 0.5));
  return {r, g, b};
}
}  // namespace

void SceneBuilder::add_box(const Eigen::Vector2d& p, const Eigen::Vector3d& size, double yaw, double elevation,
                           const std::string& mat, double color_jitter) {
  Prism& b =
      add_rect(p.x(), p.y(), size.x(), size.y(), yaw, elevation, elevation + size.z(), material(mat), GT::SURFACE_BOX);
  b.tint = jitter_tint(rng_, color_jitter);
}

void SceneBuilder::add_cylinder(const Eigen::Vector2d& p, double radius, double height, const std::string& mat,
                                double color_jitter) {
  Prism& c = add_circle(p.x(), p.y(), radius, 0, height, material(mat), GT::SURFACE_CYLINDER);
  c.tint = jitter_tint(rng_, color_jitter);
}

void SceneBuilder::add_chair(const Eigen::Vector2d& p, double yaw, const Eigen::Vector3d& size,
                             const std::string& seat_material, const std::string& frame_material) {
  const double w = size.x(), d = size.y(), back = size.z(), seat = 0.45, leg = 0.035;
  const double c = std::cos(yaw), s = std::sin(yaw);
  auto at = [&](double lx, double ly) { return Eigen::Vector2d(p.x() + c * lx - s * ly, p.y() + s * lx + c * ly); };
  const uint16_t frame = material(frame_material), cushion = material(seat_material);
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d q = at((i & 1 ? 1 : -1) * (d / 2 - leg), (i & 2 ? 1 : -1) * (w / 2 - leg));
    add_rect(q.x(), q.y(), leg, leg, yaw, 0, seat - 0.04, frame, GT::SURFACE_CHAIR);
  }
  const Eigen::Vector2d centre = at(0, 0), back_centre = at(-d / 2 + 0.025, 0);
  add_rect(centre.x(), centre.y(), d, w, yaw, seat - 0.05, seat, cushion, GT::SURFACE_CHAIR);
  add_rect(back_centre.x(), back_centre.y(), 0.05, w, yaw, seat, back, cushion, GT::SURFACE_CHAIR);
}

void SceneBuilder::add_table(const Eigen::Vector2d& p, double yaw, const Eigen::Vector3d& size,
                             const std::string& top_material, const std::string& leg_material) {
  const double l = size.x(), w = size.y(), h = size.z(), leg = 0.05;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const uint16_t legs = material(leg_material);
  for (int i = 0; i < 4; ++i) {
    const double lx = (i & 1 ? 1 : -1) * (l / 2 - leg), ly = (i & 2 ? 1 : -1) * (w / 2 - leg);
    add_rect(p.x() + c * lx - s * ly, p.y() + s * lx + c * ly, leg, leg, yaw, 0, h - 0.03, legs, GT::SURFACE_CHAIR);
  }
  add_rect(p.x(), p.y(), l, w, yaw, h - 0.03, h, material(top_material), GT::SURFACE_CHAIR);
}

void SceneBuilder::add_bench(const Eigen::Vector2d& p, double yaw, double length) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const uint16_t support = material("concrete"), seat = material("wood_light");
  for (int i = -1; i <= 1; i += 2) {
    const double lx = i * (length / 2 - 0.15);
    add_rect(p.x() + c * lx, p.y() + s * lx, 0.12, 0.42, yaw, 0, 0.40, support, GT::SURFACE_CHAIR);
  }
  add_rect(p.x(), p.y(), length, 0.45, yaw, 0.40, 0.46, seat, GT::SURFACE_CHAIR);
}

void SceneBuilder::add_car(const Eigen::Vector2d& p, double yaw) {
  static const char* kPaints[] = {"car_white", "car_red", "car_dark", "plastic_blue", "metal_grey"};
  const std::string paint = kPaints[rng_.uniform_int(0, 4)];
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double L = rng_.uniform(3.9, 4.6);
  const double W = rng_.uniform(1.7, 1.9);
  auto at = [&](double lx, double ly) { return Eigen::Vector2d(p.x() + c * lx - s * ly, p.y() + s * lx + c * ly); };
  const uint16_t body = material(paint), tyre = material("plastic_black"), glass = material("car_dark");
  for (int i = 0; i < 4; ++i) {  // wheels: the camera sees under the body between them
    const Eigen::Vector2d q = at((i & 1 ? 1 : -1) * (L / 2 - 0.75), (i & 2 ? 1 : -1) * (W / 2 - 0.12));
    add_rect(q.x(), q.y(), 0.62, 0.2, yaw, 0, 0.62, tyre, GT::SURFACE_BOX);
  }
  Prism& b = add_rect(p.x(), p.y(), L, W, yaw, 0.28, 1.0, body, GT::SURFACE_BOX);
  b.tint = jitter_tint(rng_, 0.1);
  const Eigen::Vector2d cab = at(-0.2, 0);
  Prism& g = add_rect(cab.x(), cab.y(), L * 0.5, W - 0.15, yaw, 1.0, 1.45, glass, GT::SURFACE_BOX);
  g.top_material = body;
}

void SceneBuilder::add_wall(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double height, double thickness,
                            const std::string& mat, double baseboard_height, const std::string& baseboard_material,
                            const std::vector<ElementSpec::Door>& doors) {
  const Eigen::Vector2d axis = to - from;
  const double length = axis.norm(), yaw = std::atan2(axis.y(), axis.x());
  const Eigen::Vector2d dir = axis / length;
  const uint16_t wall = material(mat);
  const uint16_t base = baseboard_height > 0 ? material(baseboard_material) : wall;
  const float u_base = static_cast<float>(rng_.uniform(0, 10));
  auto piece = [&](double s0, double s1, double z0, double z1, uint16_t m, uint8_t surface, double bb, double inset) {
    // Pieces of at most 3 m, so that their precomputed lighting varies along the wall.
    const int n = std::max(1, static_cast<int>(std::ceil((s1 - s0) / 3.0)));
    for (int i = 0; i < n; ++i) {
      const double a = s0 + (s1 - s0) * i / n, b = s0 + (s1 - s0) * (i + 1) / n;
      const Eigen::Vector2d c = from + dir * ((a + b) / 2);
      Prism& p = add_rect(c.x(), c.y(), b - a, thickness - 2 * inset, yaw, z0, z1, m, surface);
      p.u_offset = u_base + static_cast<float>((a + b) / 2);
      p.v_offset = 0;
      if (bb > 0 && z0 < bb) {
        p.base_height = static_cast<float>(bb);
        p.base_material = base;
      }
    }
  };
  std::vector<ElementSpec::Door> sorted = doors;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.offset < b.offset; });
  double s = 0;
  for (const auto& d : sorted) {
    const double d0 = std::clamp(d.offset, s, length), d1 = std::clamp(d.offset + d.width, d0, length);
    if (d0 > s + 1e-3) piece(s, d0, 0, height, wall, GT::SURFACE_WALL, baseboard_height, 0);
    if (d1 > d0 + 1e-3) {
      const double top = std::min(d.height, height);
      if (!d.open)
        piece(d0, d1, 0, top, material(d.material.empty() ? "door_wood" : d.material), GT::SURFACE_DOOR, 0, 0.01);
      if (height > top + 1e-3) piece(d0, d1, top, height, wall, GT::SURFACE_WALL, 0, 0);
    }
    s = d1;
  }
  if (length > s + 1e-3) piece(s, length, 0, height, wall, GT::SURFACE_WALL, baseboard_height, 0);
}

void SceneBuilder::add_curb(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double width, double height,
                            const std::string& mat) {
  const Eigen::Vector2d c = (from + to) / 2, axis = to - from;
  add_rect(c.x(), c.y(), axis.norm(), width, std::atan2(axis.y(), axis.x()), 0, height, material(mat),
           GT::SURFACE_CURB);
}

void SceneBuilder::add_pole(const Eigen::Vector2d& p, double diameter, double height, const std::string& mat) {
  add_circle(p.x(), p.y(), diameter / 2, 0, height, material(mat), GT::SURFACE_CYLINDER);
}

void SceneBuilder::add_lamp_post(const Eigen::Vector2d& p, double height, double emission) {
  add_pole(p, 0.14, height, "pole_metal");
  const double yaw = rng_.uniform(0, 2 * M_PI);
  const Eigen::Vector2d head = p + 0.3 * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
  const bool lit = emission > 0;
  Prism& h = add_rect(head.x(), head.y(), 0.55, 0.25, yaw, height - 0.15, height,
                      material(lit ? "lamp_head" : "metal_grey"), GT::SURFACE_CYLINDER);
  if (lit) {
    Material m = builtin_material("lamp_head");
    m.name = "lamp_head_" + std::to_string(static_cast<int>(emission));
    m.emission = emission;
    data_->materials.push_back(make_material_data(m));
    h.material = h.top_material = h.base_material = static_cast<uint16_t>(data_->materials.size() - 1);
    PointLight light;
    light.position =
        Eigen::Vector3f(static_cast<float>(head.x()), static_cast<float>(head.y()), static_cast<float>(height - 0.16));
    // A street lamp lights the ground below it to ~10-30 lux: a faint pool
    // next to its glaring head (which the camera and wet floors see directly).
    light.intensity = Rgbf(1.0f, 0.85f, 0.65f) * static_cast<float>(emission * 0.012);
    light.downward = true;
    light.glare = static_cast<float>(emission * 0.55 * 0.25);
    data_->lights.push_back(light);
  }
}

void SceneBuilder::add_ceiling_light(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double emission) {
  panels_.push_back({p, size / 2, static_cast<float>(emission)});
  PointLight light;
  light.position = Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), data_->ceiling_height - 0.01f);
  light.intensity = Rgbf(1.0f, 0.97f, 0.92f) * static_cast<float>(emission * size.x() * size.y() / M_PI);
  light.downward = true;
  data_->lights.push_back(light);
}

void SceneBuilder::add_patch(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double yaw, bool ellipse,
                             const std::string& mat) {
  FloorFeature f;
  f.kind = FloorFeature::kPatch;
  f.ellipse = ellipse;
  f.material = material(mat);
  f.cx = static_cast<float>(p.x());
  f.cy = static_cast<float>(p.y());
  f.hx = static_cast<float>(size.x() / 2);
  f.hy = static_cast<float>(size.y() / 2);
  f.cos_yaw = static_cast<float>(std::cos(yaw));
  f.sin_yaw = static_cast<float>(std::sin(yaw));
  data_->floor_features.push_back(f);
}

void SceneBuilder::add_puddle(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double yaw,
                              const std::string& mat) {
  add_patch(p, size, yaw, false, mat);
  FloorFeature& f = data_->floor_features.back();
  f.kind = FloorFeature::kPuddle;
  PuddleMask mask;
  mask.cell = 0.02f;
  mask.nx = std::max(2, static_cast<int>(std::ceil(size.x() / mask.cell)) + 1);
  mask.ny = std::max(2, static_cast<int>(std::ceil(size.y() / mask.cell)) + 1);
  const int n = 16;
  std::vector<float> coarse(n * n), fine(n * n);
  for (float& v : coarse) v = static_cast<float>(rng_.uniform(-1, 1));
  for (float& v : fine) v = static_cast<float>(rng_.uniform(-1, 1));
  mask.field.resize(static_cast<size_t>(mask.nx) * mask.ny);
  for (int j = 0; j < mask.ny; ++j)
    for (int i = 0; i < mask.nx; ++i) {
      const double lx = -f.hx + i * mask.cell, ly = -f.hy + j * mask.cell;
      const double ex = lx / f.hx, ey = ly / f.hy, r2 = ex * ex + ey * ey;
      const double noise = 0.45 * lattice_noise(coarse, n, lx / 0.35 + 3, ly / 0.35 + 5) +
                           0.15 * lattice_noise(fine, n, lx / 0.08 + 7, ly / 0.08 + 1);
      mask.field[static_cast<size_t>(j) * mask.nx + i] = static_cast<float>(std::min(1.0 - r2 + noise, 1.0 - r2));
    }
  f.mask = static_cast<int>(data_->puddle_masks.size());
  data_->puddle_masks.push_back(std::move(mask));
}

void SceneBuilder::add_pit(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double depth, double yaw,
                           bool ellipse, const std::string& mat) {
  add_patch(p, size, yaw, ellipse, mat);
  FloorFeature& f = data_->floor_features.back();
  f.kind = FloorFeature::kPit;
  f.depth = static_cast<float>(depth);
}

void SceneBuilder::add_element(const ElementSpec& e) {
  using T = ElementSpec::Type;
  auto mat_or = [&](const char* fallback) { return e.material.empty() ? std::string(fallback) : e.material; };
  switch (e.type) {
    case T::kBox: add_box(e.position, e.size, e.yaw, e.elevation, mat_or("cardboard")); break;
    case T::kCylinder: add_cylinder(e.position, e.size.x() / 2, e.size.z(), mat_or("plastic_blue")); break;
    case T::kChair: add_chair(e.position, e.yaw, e.size, mat_or("fabric_grey"), "metal_black"); break;
    case T::kTable: add_table(e.position, e.yaw, e.size, mat_or("wood_light"), "metal_grey"); break;
    case T::kWall:
      add_wall(e.position, e.end, e.size.z(), std::max(0.02, e.size.y()), mat_or("paint_white"), e.baseboard_height,
               e.baseboard_material.empty() ? "baseboard_black" : e.baseboard_material, e.doors);
      break;
    case T::kPole: add_pole(e.position, e.size.x(), e.size.z(), mat_or("pole_metal")); break;
    case T::kLampPost: add_lamp_post(e.position, e.size.z(), e.intensity); break;
    case T::kCurb: add_curb(e.position, e.end, e.size.y(), e.size.z(), mat_or("curb_concrete")); break;
    case T::kFloorPatch: add_patch(e.position, e.size.head<2>(), e.yaw, e.shape == "ellipse", mat_or("rug_red")); break;
    case T::kPuddle: add_puddle(e.position, e.size.head<2>(), e.yaw, mat_or("water")); break;
    case T::kPit:
      add_pit(e.position, e.size.head<2>(), e.depth, e.yaw, e.shape == "ellipse", mat_or("pit_soil"));
      break;
    case T::kLight: add_ceiling_light(e.position, e.size.head<2>(), e.intensity > 0 ? e.intensity : 80.0); break;
  }
}

double SceneBuilder::gap_to_placed(const Eigen::Vector2d& p, double radius, Placed which) const {
  double gap = 1e9;
  for (const Prism& q : data_->prisms) {
    if (q.z1 < 0.05f || q.z0 > 1.0f) continue;
    const bool wall = q.surface == GT::SURFACE_WALL || q.surface == GT::SURFACE_DOOR;
    if ((which == Placed::kWalls && !wall) || (which == Placed::kNotWalls && wall)) continue;
    gap = std::min(gap, footprint_distance(q, p.x(), p.y()) - radius);
  }
  if (which != Placed::kWalls)
    for (const FloorFeature& f : data_->floor_features)
      if (f.kind == FloorFeature::kPit) gap = std::min(gap, feature_distance(f, p.x(), p.y()) - radius);
  return gap;
}

std::shared_ptr<SceneData> SceneBuilder::finish() {
  build_plan_grid(*data_);
  compute_lighting(*data_);
  build_ceiling(*this);
  return data_;
}

}  // namespace ivoa::sim::detail
