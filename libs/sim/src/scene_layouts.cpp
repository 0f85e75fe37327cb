// Procedural layouts: rooms, corridors, office blocks and open outdoor areas,
// their obstacles, floor details (rugs, wet patches, puddles, pits) and lights.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "geometry.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "scene_builder.hpp"

namespace ivoa::sim::detail {
namespace {

using GT = sim_ground_truth_t;
using V2 = Eigen::Vector2d;

double draw(Rng& rng, const Range& r) { return rng.uniform(r.min, r.max); }
int draw_count(Rng& rng, const Range& r) { return static_cast<int>(std::floor(rng.uniform(r.min, r.max + 0.999))); }

template <class T>
const T& one_of(Rng& rng, const std::vector<T>& v) {
  return v[static_cast<size_t>(rng.uniform_int(0, static_cast<int>(v.size()) - 1))];
}

struct Box2 {
  double x0, y0, x1, y1;
  double w() const { return x1 - x0; }
  double h() const { return y1 - y0; }
};

// A wall side with doors drawn per ~3 m piece.
std::vector<ElementSpec::Door> random_doors(SceneBuilder& b, double length, double probability, bool open) {
  std::vector<ElementSpec::Door> doors;
  Rng& rng = b.rng();
  const int pieces = std::max(1, static_cast<int>(length / 3.0));
  const double piece = length / pieces;
  for (int i = 0; i < pieces; ++i) {
    if (piece < 1.4 || !rng.chance(probability)) continue;
    ElementSpec::Door d;
    d.width = open ? rng.uniform(1.1, 1.4) : rng.uniform(0.85, 1.0);
    d.width = std::min(d.width, piece - 0.3);
    d.offset = i * piece + rng.uniform(0.15, piece - d.width - 0.15);
    d.height = 2.05;
    d.open = open;
    if (!open && !b.spec().walls.door_materials.empty()) d.material = one_of(rng, b.spec().walls.door_materials);
    doors.push_back(d);
  }
  return doors;
}

// One wall with its material, baseboard and doors drawn from the spec.
void random_wall(SceneBuilder& b, const V2& from, const V2& to, double height,
                 const std::vector<ElementSpec::Door>& doors, const std::string& material = "") {
  const auto& spec = b.spec();
  Rng& rng = b.rng();
  const std::string mat = !material.empty() ? material : b.pick_wall(spec.walls.materials);
  double bb = 0;
  std::string bb_mat;
  if (!spec.walls.baseboard_materials.empty() && rng.chance(spec.phenomena.dark_stripes)) {
    bb = draw(rng, spec.walls.baseboard_height);
    bb_mat = one_of(rng, spec.walls.baseboard_materials);
  }
  b.add_wall(from, to, height, draw(rng, spec.walls.thickness), mat, bb, bb_mat, doors);
}

// Four walls around an interior rectangle (outside it).
void enclose(SceneBuilder& b, const Box2& r, double height, double door_probability) {
  const double t = 0.07;
  const V2 corners[4] = {{r.x0 - t, r.y0 - t}, {r.x1 + t, r.y0 - t}, {r.x1 + t, r.y1 + t}, {r.x0 - t, r.y1 + t}};
  for (int i = 0; i < 4; ++i) {
    const V2 a = corners[i], c = corners[(i + 1) % 4];
    random_wall(b, a, c, height, random_doors(b, (c - a).norm(), door_probability, false));
  }
}

void set_bounds(SceneBuilder& b, const Box2& r) {
  b.data().bounds = Eigen::AlignedBox2d(V2(r.x0, r.y0), V2(r.x1, r.y1));
}

void layout_room(SceneBuilder& b) {
  Rng& rng = b.rng();
  const auto& l = b.spec().layout;
  const double w = draw(rng, l.width);
  const double d = draw(rng, l.depth);
  const Box2 r{-w / 2, -d / 2, w / 2, d / 2};
  set_bounds(b, r);
  b.data().floor_material = b.material(b.pick_floor(b.spec().floor.materials));
  enclose(b, r, b.data().ceiling_height, l.door_probability);
}

void layout_corridor(SceneBuilder& b) {
  Rng& rng = b.rng();
  const auto& l = b.spec().layout;
  const double len = draw(rng, l.corridor_length);
  const double w = draw(rng, l.corridor_width);
  const Box2 r{-len / 2, -w / 2, len / 2, w / 2};
  set_bounds(b, r);
  b.data().floor_material = b.material(b.pick_floor(b.spec().floor.materials));
  const double t = 0.07, h = b.data().ceiling_height;
  // Long walls get doors (offices along the corridor); the ends are plain.
  random_wall(b, {r.x0 - t, r.y0 - t}, {r.x1 + t, r.y0 - t}, h, random_doors(b, len, l.door_probability, false));
  random_wall(b, {r.x1 + t, r.y1 + t}, {r.x0 - t, r.y1 + t}, h, random_doors(b, len, l.door_probability, false));
  random_wall(b, {r.x1 + t, r.y0 - t}, {r.x1 + t, r.y1 + t}, h, {});
  random_wall(b, {r.x0 - t, r.y1 + t}, {r.x0 - t, r.y0 - t}, h, {});
}

void layout_office(SceneBuilder& b) {
  Rng& rng = b.rng();
  const auto& l = b.spec().layout;
  const double w = draw(rng, l.width);
  const double d = draw(rng, l.depth);
  const Box2 r{-w / 2, -d / 2, w / 2, d / 2};
  set_bounds(b, r);
  const std::string base = b.pick_floor(b.spec().floor.materials);
  b.data().floor_material = b.material(base);
  const double h = b.data().ceiling_height;
  enclose(b, r, h, l.door_probability);
  const int nx = std::max(1, static_cast<int>(std::lround(w / draw(rng, l.room_size))));
  const int ny = std::max(1, static_cast<int>(std::lround(d / draw(rng, l.room_size))));
  const double cw = w / nx, ch = d / ny;
  // Partition walls with one open doorway per room they separate.
  auto doorways = [&](int cells, double cell) {
    std::vector<ElementSpec::Door> doors;
    for (int i = 0; i < cells; ++i) {
      ElementSpec::Door door;
      door.open = true;
      door.width = std::min(cell - 0.4, rng.uniform(1.1, 1.5));
      door.offset = i * cell + rng.uniform(0.2, cell - door.width - 0.2);
      doors.push_back(door);
    }
    return doors;
  };
  for (int i = 1; i < nx; ++i) random_wall(b, {r.x0 + i * cw, r.y0}, {r.x0 + i * cw, r.y1}, h, doorways(ny, ch));
  for (int j = 1; j < ny; ++j) random_wall(b, {r.x0, r.y0 + j * ch}, {r.x1, r.y0 + j * ch}, h, doorways(nx, cw));
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      if (rng.chance(0.5))
        b.add_patch({r.x0 + (i + 0.5) * cw, r.y0 + (j + 0.5) * ch}, {cw, ch}, 0, false,
                    b.pick_floor(b.spec().floor.materials));
}

void layout_open(SceneBuilder& b) {
  Rng& rng = b.rng();
  const auto& l = b.spec().layout;
  const double w = draw(rng, l.width);
  const double d = draw(rng, l.depth);
  const Box2 r{-w / 2, -d / 2, w / 2, d / 2};
  set_bounds(b, r);
  b.data().floor_material = b.material(b.pick_floor(b.spec().floor.materials));
  // Facades or hedges on every side; they are what the horizon shows.
  const V2 corners[4] = {
      {r.x0 - 0.5, r.y0 - 0.5}, {r.x1 + 0.5, r.y0 - 0.5}, {r.x1 + 0.5, r.y1 + 0.5}, {r.x0 - 0.5, r.y1 + 0.5}};
  for (int i = 0; i < 4; ++i) {
    const V2 a = corners[i], c = corners[(i + 1) % 4];
    if (rng.chance(0.65) && !b.spec().walls.materials.empty()) {
      const std::string mat = b.pick_wall(b.spec().walls.materials);
      b.add_wall(a, c, draw(rng, l.facade_height), 0.6, mat, 0, "", {});
    } else {
      b.add_wall(a, c, rng.uniform(1.2, 2.2), 0.8, "hedge", 0, "", {});
      b.data().prisms.back().surface = GT::SURFACE_WALL;
    }
  }
}

void layout_none(SceneBuilder& b) {
  Rng& rng = b.rng();
  const auto& l = b.spec().layout;
  const double w = draw(rng, l.width);
  const double d = draw(rng, l.depth);
  Eigen::AlignedBox2d bounds(V2(-w / 2, -d / 2), V2(w / 2, d / 2));
  for (const ElementSpec& e : b.spec().elements) {
    bounds.extend(e.position);
    if (e.type == ElementSpec::Type::kWall || e.type == ElementSpec::Type::kCurb) bounds.extend(e.end);
  }
  b.data().bounds = bounds;
  b.data().floor_material = b.material(b.spec().floor.materials.front());
}

// Footprint radius and builder for each obstacle kind.
struct Kind {
  double radius;
  std::function<void(const V2&)> build;
};

Kind make_kind(SceneBuilder& b, const std::string& kind) {
  Rng& rng = b.rng();
  const auto& o = b.spec().obstacles;
  const bool night = b.spec().lighting.night;
  auto palette = [&] { return b.pick_obstacle(o.materials); };
  const double jitter = o.color_jitter;
  if (kind == "box" || kind == "cabinet" || kind == "planter") {
    const double sx = draw(rng, o.box_size);
    const double sy = kind == "cabinet" ? rng.uniform(0.35, 0.6) : draw(rng, o.box_size);
    double h = draw(rng, o.box_height);
    if (kind == "cabinet") h = rng.uniform(1.0, 1.9);
    if (kind == "planter") h = rng.uniform(0.35, 0.7);
    const double yaw = rng.chance(0.5) ? rng.uniform(0, M_PI) : 0.0;
    const std::string mat = palette();
    const bool stack = kind == "box" && rng.chance(0.25);
    return {std::hypot(sx, sy) / 2, [&b, sx, sy, h, yaw, mat, stack, jitter, kind](const V2& p) {
              b.add_box(p, {sx, sy, h}, yaw, 0, mat, jitter);
              if (kind == "planter") b.data().prisms.back().top_material = b.material("soil");
              if (stack) b.add_box(p, {sx * 0.7, sy * 0.7, h * 0.6}, yaw + 0.3, h, mat, jitter);
            }};
  }
  if (kind == "cylinder" || kind == "bin" || kind == "bollard") {
    double r = rng.uniform(0.12, 0.35);
    double h = rng.uniform(0.3, 1.2);
    if (kind == "bin") r = 0.18 + 0.12 * (r - 0.12) / 0.23, h = 0.55 + 0.45 * (h - 0.3) / 0.9;
    if (kind == "bollard") r = 0.06 + 0.06 * (r - 0.12) / 0.23, h = 0.7 + 0.3 * (h - 0.3) / 0.9;
    const std::string mat = palette();
    return {r, [&b, r, h, mat, jitter](const V2& p) { b.add_cylinder(p, r, h, mat, jitter); }};
  }
  if (kind == "chair") {
    static const char* kSeats[] = {"fabric_grey", "fabric_blue", "plastic_black", "plastic_red", "wood_light"};
    const std::string seat = kSeats[rng.uniform_int(0, 4)];
    const std::string frame = rng.chance(0.5) ? "metal_black" : "metal_grey";
    const double yaw = rng.uniform(0, 2 * M_PI);
    return {0.35, [&b, seat, frame, yaw](const V2& p) { b.add_chair(p, yaw, {0.46, 0.46, 0.88}, seat, frame); }};
  }
  if (kind == "table") {
    const double len = rng.uniform(0.9, 1.6);
    const double wid = rng.uniform(0.6, 0.8);
    const double yaw = rng.chance(0.7) ? 0.0 : rng.uniform(0, M_PI);
    const std::string top = rng.chance(0.5) ? "wood_light" : "plastic_white";
    return {std::hypot(len, wid) / 2, [&b, len, wid, yaw, top](const V2& p) {
              b.add_table(p, yaw, {len, wid, 0.73}, top, "metal_grey");
            }};
  }
  if (kind == "pole") {
    const double h = rng.uniform(1.5, 3.0);
    const double dia = rng.uniform(0.05, 0.12);
    return {dia / 2, [&b, h, dia](const V2& p) { b.add_pole(p, dia, h, "pole_metal"); }};
  }
  if (kind == "lamp_post") {
    const double h = rng.uniform(3.5, 4.5);
    const double emission = night ? rng.uniform(150, 300) : 0.0;
    return {0.45, [&b, h, emission](const V2& p) { b.add_lamp_post(p, h, emission); }};
  }
  if (kind == "bench") {
    const double len = rng.uniform(1.2, 2.0);
    const double yaw = rng.uniform(0, M_PI);
    return {len / 2 + 0.05, [&b, len, yaw](const V2& p) { b.add_bench(p, yaw, len); }};
  }
  if (kind == "car") {
    const double yaw = rng.chance(0.8) ? (rng.chance(0.5) ? 0.0 : M_PI / 2) : rng.uniform(0, M_PI);
    return {2.4, [&b, yaw](const V2& p) { b.add_car(p, yaw); }};
  }
  if (kind == "curb") {
    const double len = rng.uniform(1.5, 5.0);
    const double yaw = rng.chance(0.7) ? 0.0 : M_PI / 2;
    const double h = rng.uniform(0.1, 0.16);
    return {len / 2, [&b, len, yaw, h](const V2& p) {
              const V2 axis(std::cos(yaw), std::sin(yaw));
              b.add_curb(p - axis * len / 2, p + axis * len / 2, 0.15, h, "curb_concrete");
            }};
  }
  throw std::logic_error("make_kind: no shape for obstacle kind '" + kind + "' (validate() checks the kinds)");
}

// A free spot for a circle of radius r: away from everything by min_gap, or
// touching a wall (objects often stand against walls).
bool find_spot(SceneBuilder& b, double r, double min_gap, V2& out) {
  Rng& rng = b.rng();
  const auto& box = b.data().bounds;
  for (int attempt = 0; attempt < 60; ++attempt) {
    const double px =
        rng.uniform(box.min().x() + r + 0.05, std::max(box.min().x() + r + 0.06, box.max().x() - r - 0.05));
    const double py =
        rng.uniform(box.min().y() + r + 0.05, std::max(box.min().y() + r + 0.06, box.max().y() - r - 0.05));
    const V2 p(px, py);
    const double wall_gap = b.gap_to_placed(p, r, SceneBuilder::Placed::kWalls);
    if (wall_gap < 0.02 || b.gap_to_placed(p, r, SceneBuilder::Placed::kNotWalls) < min_gap) continue;
    if (wall_gap >= min_gap || wall_gap < 0.25) {  // free standing, or against a wall
      out = p;
      return true;
    }
  }
  return false;
}

}  // namespace

void build_layout(SceneBuilder& b) {
  switch (b.spec().layout.type) {
    case LayoutType::kRoom: layout_room(b); break;
    case LayoutType::kCorridor: layout_corridor(b); break;
    case LayoutType::kOffice: layout_office(b); break;
    case LayoutType::kOpen: layout_open(b); break;
    case LayoutType::kNone: layout_none(b); break;
  }
}

void place_obstacles(SceneBuilder& b) {
  const auto& o = b.spec().obstacles;
  Rng& rng = b.rng();
  const int n = draw_count(rng, o.count);
  if (n <= 0 || o.kinds.empty()) return;
  std::vector<double> weights;
  for (const auto& k : o.kinds) weights.push_back(k.second);
  // Parking lots get painted bay lines when cars are among the kinds.
  for (int i = 0; i < n; ++i) {
    const std::string& kind = o.kinds[rng.weighted(weights)].first;
    const Kind k = make_kind(b, kind);
    V2 p;
    if (find_spot(b, k.radius, o.min_gap, p)) k.build(p);
  }
}

// A uniformly random floor point at least `margin` inside the scene's bounds.
V2 random_floor_point(SceneBuilder& b, double margin) {
  const auto& box = b.data().bounds;
  Rng& rng = b.rng();
  const double x = rng.uniform(box.min().x() + margin, std::max(box.min().x() + margin, box.max().x() - margin));
  const double y = rng.uniform(box.min().y() + margin, std::max(box.min().y() + margin, box.max().y() - margin));
  return V2(x, y);
}

// (In these placers every random draw is its own statement: argument
// evaluation order is unspecified, and the scenes must not depend on it.)

// Rugs, mats and other floor materials laid on the floor.
void place_floor_patches(SceneBuilder& b, bool outdoor) {
  const auto& floor = b.spec().floor;
  Rng& rng = b.rng();
  if (floor.patch_materials.empty()) return;
  const int n = draw_count(rng, floor.patch_count);
  for (int i = 0; i < n; ++i) {
    const double sx = draw(rng, floor.patch_size);
    const double sy = draw(rng, floor.patch_size);
    const double yaw = outdoor ? rng.uniform(0, M_PI) : (rng.chance(0.8) ? 0.0 : rng.uniform(0, M_PI));
    const V2 p = random_floor_point(b, 0.3);
    const bool ellipse = rng.chance(outdoor ? 0.5 : 0.2);
    b.add_patch(p, {sx, sy}, yaw, ellipse, one_of(rng, floor.patch_materials));
  }
}

// Wet patches and puddles: water films and mirror-like pools.
void place_wet_patches(SceneBuilder& b, bool outdoor) {
  Rng& rng = b.rng();
  const int wet = draw_count(rng, b.spec().phenomena.wet_patches);
  const std::string base = b.data().materials[b.data().floor_material].spec.name;
  const std::string wet_variant =
      has_builtin_material(base + "_wet") ? base + "_wet" : (outdoor ? "asphalt_wet" : "water");
  for (int i = 0; i < wet; ++i) {
    const V2 p = random_floor_point(b, 0.5);
    const bool puddle = rng.chance(outdoor ? 0.55 : 0.7);
    const double s = puddle ? (outdoor ? rng.uniform(0.6, 2.8) : rng.uniform(0.4, 1.4))
                            : (outdoor ? rng.uniform(2.0, 6.0) : rng.uniform(1.0, 2.5));
    const double aspect = rng.uniform(0.5, 1.0);
    const double yaw = rng.uniform(0, M_PI);
    if (puddle) b.add_puddle(p, {s, s * aspect}, yaw, "water");
    else b.add_patch(p, {s, s * aspect}, yaw, true, wet_variant);
  }
}

// Holes in the ground, kept clear of what is already placed (40 tries each).
void place_pits(SceneBuilder& b, bool outdoor) {
  const auto& pits = b.spec().pits;
  Rng& rng = b.rng();
  if (!rng.chance(pits.probability)) return;
  const int n = draw_count(rng, pits.count);
  for (int i = 0; i < n; ++i) {
    const double sx = draw(rng, pits.size);
    const double sy = draw(rng, pits.size);
    const double depth = draw(rng, pits.depth);
    const double yaw = rng.uniform(0, M_PI);
    const bool ellipse = rng.chance(0.4);
    const double r = std::hypot(sx, sy) / 2;
    for (int attempt = 0; attempt < 40; ++attempt) {
      const V2 p = random_floor_point(b, r + 0.3);
      if (b.gap_to_placed(p, r) < 0.9) continue;
      b.add_pit(p, {sx, sy}, depth, yaw, ellipse, outdoor ? "pit_soil" : "concrete");
      break;
    }
  }
}

void place_floor_details(SceneBuilder& b) {
  const bool outdoor = b.spec().environment == Environment::kOutdoor;
  place_floor_patches(b, outdoor);
  place_wet_patches(b, outdoor);
  place_pits(b, outdoor);
}

// A grid of ceiling panels over the scene's bounds, some of them glaring.
void place_ceiling_lights(SceneBuilder& b) {
  const auto& l = b.spec().lighting;
  SceneData& d = b.data();
  Rng& rng = b.rng();
  d.ambient = Rgbf(static_cast<float>(draw(rng, l.ambient)));
  const double spacing = draw(rng, l.light_spacing);
  const bool strip = rng.chance(0.4);
  const V2 size = strip ? V2(1.2, 0.3) : V2(0.6, 0.6);
  const auto& box = d.bounds;
  const int nx = std::max(1, static_cast<int>(box.sizes().x() / spacing + 0.5));
  const int ny = std::max(1, static_cast<int>(box.sizes().y() / spacing + 0.5));
  const double sx = box.sizes().x() / nx, sy = box.sizes().y() / ny;
  const double emission = draw(rng, l.light_emission);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const double boost = rng.chance(b.spec().phenomena.glare) ? rng.uniform(2.0, 3.5) : 1.0;  // glaring fixtures
      b.add_ceiling_light({box.min().x() + (i + 0.5) * sx, box.min().y() + (j + 0.5) * sy}, size, emission * boost);
    }
}

// Outdoors: a night sky, an overcast one, or sun (low and glaring by the glare phenomenon).
void set_sky(SceneBuilder& b) {
  const auto& l = b.spec().lighting;
  SceneData& d = b.data();
  Rng& rng = b.rng();
  SkyData& sky = d.sky;
  const float sky_e = static_cast<float>(draw(rng, l.sky_irradiance));
  if (l.night) {
    d.ambient = Rgbf(0.008f, 0.008f, 0.012f);
    sky.zenith = Rgbf(0.004f, 0.005f, 0.01f);
    sky.horizon = Rgbf(0.02f, 0.018f, 0.02f);
    sky.has_sun = false;
  } else if (rng.chance(l.overcast_probability)) {
    d.ambient = Rgbf(sky_e * 1.3f);
    sky.zenith = Rgbf(sky_e * 1.1f);
    sky.horizon = Rgbf(sky_e * 1.5f);
    sky.has_sun = false;
  } else {
    d.ambient = Rgbf(sky_e * 0.9f, sky_e * 0.95f, sky_e * 1.1f);
    sky.zenith = Rgbf(sky_e * 0.35f, sky_e * 0.55f, sky_e * 1.1f);
    sky.horizon = Rgbf(sky_e * 1.1f, sky_e * 1.15f, sky_e * 1.25f);
    sky.has_sun = true;
    const bool low_sun = rng.chance(b.spec().phenomena.glare);
    const double elev = (low_sun ? rng.uniform(4, 12) : draw(rng, l.sun_elevation_deg)) * M_PI / 180;
    const double az = draw(rng, l.sun_azimuth_deg) * M_PI / 180;
    sky.sun_dir =
        Eigen::Vector3f(static_cast<float>(std::cos(elev) * std::cos(az)),
                        static_cast<float>(std::cos(elev) * std::sin(az)), static_cast<float>(std::sin(elev)));
    const float e = static_cast<float>(draw(rng, l.sun_irradiance));
    sky.sun_irradiance = Rgbf(e, e * 0.96f, e * 0.88f) * (low_sun ? 0.7f : 1.0f);
  }
}

// A low-light session dims every source alike.
void dim_every_source(SceneBuilder& b, float level) {
  SceneData& d = b.data();
  d.ambient = d.ambient * level;
  d.sky.zenith = d.sky.zenith * level;
  d.sky.horizon = d.sky.horizon * level;
  d.sky.sun_irradiance = d.sky.sun_irradiance * level;
  for (PointLight& p : d.lights) p.intensity = p.intensity * level, p.glare *= level;
  for (auto& panel : b.panels()) panel.emission *= level;
  for (MaterialData& m : d.materials) m.emission = m.emission * level;
}

void place_lights(SceneBuilder& b) {
  Rng& rng = b.rng();
  const float level = rng.chance(b.spec().phenomena.low_light)
                          ? static_cast<float>(draw(rng, b.spec().lighting.low_light_factor))
                          : 1.0f;
  b.data().light_level = level;
  if (b.data().environment == Environment::kIndoor) place_ceiling_lights(b);
  else set_sky(b);
  dim_every_source(b, level);
}

void choose_start(SceneBuilder& b) {
  SceneData& d = b.data();
  if (b.spec().start) {
    d.start = *b.spec().start;
    return;
  }
  Rng& rng = b.rng();
  const auto& box = d.bounds;
  double best = -1e9;
  for (int i = 0; i < 400; ++i) {
    const double px = rng.uniform(box.min().x() + 0.4, box.max().x() - 0.4);
    const double py = rng.uniform(box.min().y() + 0.4, box.max().y() - 0.4);
    const V2 p(px, py);
    const double gap =
        std::min(b.gap_to_placed(p, 0), std::min(std::min(p.x() - box.min().x(), box.max().x() - p.x()),
                                                 std::min(p.y() - box.min().y(), box.max().y() - p.y())));
    if (gap > best) {
      best = gap;
      d.start = Pose2D{p.x(), p.y(), rng.uniform(-M_PI, M_PI)};
    }
    if (gap > 1.0) break;
  }
}

void build_ceiling(SceneBuilder& b) {
  SceneData& d = b.data();
  if (!d.has_ceiling) return;
  const uint16_t mat = b.material("ceiling_tiles");
  const Texture& tex = *d.materials[mat].texture;
  const Rgbf irradiance = d.ambient * 0.8f;
  const auto box = d.bounds;
  const float margin = 1.0f;
  const float x0 = static_cast<float>(box.min().x()) - margin, y0 = static_cast<float>(box.min().y()) - margin;
  const float w = static_cast<float>(box.sizes().x()) + 2 * margin,
              h = static_cast<float>(box.sizes().y()) + 2 * margin;
  const float cell = std::max(0.03f, std::max(w, h) / 1024.0f);
  const int nx = static_cast<int>(std::ceil(w / cell)), ny = static_cast<int>(std::ceil(h / cell));
  std::vector<Rgbf> values(static_cast<size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const float x = x0 + (static_cast<float>(i) + 0.5f) * cell, y = y0 + (static_cast<float>(j) + 0.5f) * cell;
      Rgbf v = tex.sample(x, y, cell) * irradiance;
      for (const auto& p : b.panels())
        if (std::abs(x - p.centre.x()) <= p.half.x() && std::abs(y - p.centre.y()) <= p.half.y())
          v = Rgbf(1.0f, 0.97f, 0.92f) * p.emission;
      values[static_cast<size_t>(j) * nx + i] = v;
    }
  d.ceiling_radiance = RadianceMap(x0, y0, cell, nx, ny, std::move(values), 8);
}

}  // namespace ivoa::sim::detail
