#include "tracer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::sim::detail {
namespace {

using GT = sim_ground_truth_t;

float wrap_angle(float a) {
  while (a > static_cast<float>(M_PI)) a -= static_cast<float>(2 * M_PI);
  while (a <= -static_cast<float>(M_PI)) a += static_cast<float>(2 * M_PI);
  return a;
}

float pow5(float x) {
  const float x2 = x * x;
  return x2 * x2 * x;
}

// 1/sqrt(x) to ~0.2% (bit trick and one Newton step; pure IEEE arithmetic,
// so deterministic): only used to pick a mip level.
float approx_rsqrt(float x) {
  uint32_t i;
  std::memcpy(&i, &x, sizeof i);
  i = 0x5f3759dfu - (i >> 1);
  float y;
  std::memcpy(&y, &i, sizeof y);
  return y * (1.5f - 0.5f * x * y * y);
}

// atan2 to ~1e-4 rad: only used for texture coordinates around cylinders.
float fast_atan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay);
  if (mx == 0) return 0;
  const float a = std::min(ax, ay) / mx, s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0) r = 3.14159274f - r;
  return y < 0 ? -r : r;
}

// Where on a solid a ray landed: its normal, texture coordinates, material.
struct SolidPoint {
  const Prism* prism;
  float nx, ny, nz;
  float u, v, z;
  uint16_t material;
  bool base;  // on the baseboard band
};

}  // namespace

Tracer::Tracer(const SceneData& scene, const CameraRays& rays, const Pose2D& pose, bool accelerate)
    : scene_(scene), rays_(rays), pose_(pose) {
  px_ = static_cast<float>(pose.x);
  py_ = static_cast<float>(pose.y);
  cos_yaw_ = static_cast<float>(std::cos(pose.yaw));
  sin_yaw_ = static_cast<float>(std::sin(pose.yaw));
  const Eigen::Vector2d o = robot_to_world(pose, rays.origin().x(), rays.origin().y());
  ox_ = static_cast<float>(o.x());
  oy_ = static_cast<float>(o.y());
  oz_ = static_cast<float>(rays.origin().z());
  if (scene.has_ceiling) s_ceiling_up_ = scene.ceiling_height - oz_;
  build_candidates(accelerate);
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const PointLight& l = scene.lights[i];
    if (l.glare > 0 && std::hypot(l.position.x() - ox_, l.position.y() - oy_) < 30.0f)
      glare_lights_.push_back(static_cast<uint32_t>(i));
  }
}

Tracer::Candidate Tracer::make_candidate(uint32_t prism) const {
  const Prism& p = scene_.prisms[prism];
  Candidate c;
  c.prism = prism;
  c.circle = p.shape == Prism::kCircle;
  c.hx = p.hx;
  c.hy = p.hy;
  c.z0 = p.z0;
  c.z1 = p.z1;
  if (c.circle) {
    const float d = std::hypot(p.cx - ox_, p.cy - oy_);
    c.c = cos_yaw_;
    c.s = sin_yaw_;
    c.lox = ox_ - p.cx;
    c.loy = oy_ - p.cy;
    c.s_min = std::max(0.0f, d - p.hx);
  } else {
    const float theta = std::atan2(p.sin_yaw, p.cos_yaw);
    c.c = std::cos(static_cast<float>(pose_.yaw) - theta);
    c.s = std::sin(static_cast<float>(pose_.yaw) - theta);
    to_local(p, ox_, oy_, c.lox, c.loy);
    c.s_min = static_cast<float>(std::max(0.0, footprint_distance(p, ox_, oy_)));
  }
  return c;
}

std::pair<float, float> Tracer::azimuth_extent(const Prism& p, float s_min) const {
  if (s_min <= 0.01f)  // the camera is inside or on the footprint: every direction
    return {-static_cast<float>(M_PI), static_cast<float>(M_PI)};
  const float dxw = p.cx - ox_, dyw = p.cy - oy_;
  const float centre = std::atan2(dyw, dxw);
  if (p.shape == Prism::kCircle) {
    const float half = std::asin(std::min(1.0f, p.hx / std::hypot(dxw, dyw)));
    return {centre - half, centre + half};
  }
  float mn = 0, mx = 0;  // the corners' angles from the centre's direction
  for (int k = 0; k < 4; ++k) {
    const float lx = (k & 1) ? p.hx : -p.hx, ly = (k & 2) ? p.hy : -p.hy;
    const float wx = p.cx + p.cos_yaw * lx - p.sin_yaw * ly - ox_, wy = p.cy + p.sin_yaw * lx + p.cos_yaw * ly - oy_;
    const float a = wrap_angle(std::atan2(wy, wx) - centre);
    mn = std::min(mn, a);
    mx = std::max(mx, a);
  }
  return {centre + mn, centre + mx};
}

void Tracer::build_candidates(bool accelerate) {
  std::vector<Candidate> all;
  all.reserve(scene_.prisms.size());
  for (size_t i = 0; i < scene_.prisms.size(); ++i) all.push_back(make_candidate(static_cast<uint32_t>(i)));
  if (!accelerate) {
    brute_force_ = true;
    candidates_ = std::move(all);
    bin_start_ = {0, static_cast<uint32_t>(candidates_.size())};
    return;
  }
  // Each candidate's azimuth bins, in the robot frame: up to three spans of
  // bins, as the extent may wrap around +-pi.
  const int num_bins = rays_.num_bins();
  const float az0 = rays_.az_min(), bw = rays_.bin_width();
  std::vector<std::pair<int, int>> spans;  // bin ranges (inclusive)
  std::vector<size_t> span_owner;
  for (size_t i = 0; i < all.size(); ++i) {
    auto [lo, hi] = azimuth_extent(scene_.prisms[i], all[i].s_min);
    lo -= static_cast<float>(pose_.yaw);
    hi -= static_cast<float>(pose_.yaw);
    const float shift = wrap_angle(lo) - lo;  // bring lo into (-pi, pi]
    lo += shift;
    hi += shift;
    for (int k = -1; k <= 1; ++k) {
      const float a = lo + static_cast<float>(k * 2 * M_PI), b = hi + static_cast<float>(k * 2 * M_PI);
      const int b0 = std::max(0, static_cast<int>(std::floor((a - az0) / bw)));
      const int b1 = std::min(num_bins - 1, static_cast<int>(std::floor((b - az0) / bw)));
      if (b0 <= b1) {
        spans.emplace_back(b0, b1);
        span_owner.push_back(i);
      }
    }
  }
  fill_bins(all, spans, span_owner);
}

void Tracer::fill_bins(const std::vector<Candidate>& all, const std::vector<std::pair<int, int>>& spans,
                       const std::vector<size_t>& span_owner) {
  const size_t num_bins = static_cast<size_t>(rays_.num_bins());
  std::vector<uint32_t> count(num_bins + 1, 0);
  for (const auto& [b0, b1] : spans)
    for (int b = b0; b <= b1; ++b) ++count[static_cast<size_t>(b)];
  bin_start_.assign(num_bins + 1, 0);
  for (size_t b = 0; b < num_bins; ++b) bin_start_[b + 1] = bin_start_[b] + count[b];
  candidates_.resize(bin_start_.back());
  std::vector<uint32_t> fill(bin_start_.begin(), bin_start_.end() - 1);
  for (size_t k = 0; k < spans.size(); ++k)
    for (int b = spans[k].first; b <= spans[k].second; ++b)
      candidates_[fill[static_cast<size_t>(b)]++] = all[span_owner[k]];
  // Nearest first; ties by index, so the order does not depend on the sort.
  for (size_t b = 0; b < num_bins; ++b)
    std::sort(candidates_.begin() + bin_start_[b], candidates_.begin() + bin_start_[b + 1],
              [](const Candidate& x, const Candidate& y) {
                return x.s_min < y.s_min || (x.s_min == y.s_min && x.prism < y.prism);
              });
}

inline Tracer::Ray Tracer::make_ray(const PixelRay& r) const {
  Ray ray;
  ray.ux = r.ux;
  ray.uy = r.uy;
  ray.wx = cos_yaw_ * r.ux - sin_yaw_ * r.uy;
  ray.wy = sin_yaw_ * r.ux + cos_yaw_ * r.uy;
  ray.slope = r.slope;
  ray.inv_slope = r.inv_slope;
  ray.len = r.len;
  ray.inv_len = r.inv_len;
  ray.bin = r.bin;
  return ray;
}

inline bool Tracer::bin_may_hit(const Ray& ray, float s_hi) const {
  if (brute_force_) return !candidates_.empty();
  const size_t first = bin_start_[static_cast<size_t>(ray.bin)], last = bin_start_[static_cast<size_t>(ray.bin) + 1];
  return first < last && candidates_[first].s_min <= s_hi;
}

void Tracer::nearest(const Ray& ray, float s_lo, float s_hi, bool mirrored, Hit& best) const {
  best.s = s_hi;
  best.candidate = -1;
  const size_t begin = brute_force_ ? 0 : bin_start_[static_cast<size_t>(ray.bin)];
  const size_t end = brute_force_ ? candidates_.size() : bin_start_[static_cast<size_t>(ray.bin) + 1];
  for (size_t k = begin; k < end; ++k) {
    const Candidate& c = candidates_[k];
    if (!brute_force_ && c.s_min > best.s) break;
    const float dx = c.c * ray.ux - c.s * ray.uy, dy = c.s * ray.ux + c.c * ray.uy;
    float t_in, t_out;
    Face face = kFaceRound;
    if (c.circle) circle_interval(c.lox, c.loy, dx, dy, c.hx, t_in, t_out);
    else rect_interval(c.lox, c.loy, dx, dy, c.hx, c.hy, t_in, t_out, face);
    if (!(t_in <= t_out) || t_out < s_lo) continue;
    const float zlo = mirrored ? -c.z1 : c.z0, zhi = mirrored ? -c.z0 : c.z1;
    const float a = (zlo - oz_) * ray.inv_slope, b = (zhi - oz_) * ray.inv_slope;
    float entry = t_in;
    if (std::min(a, b) > entry) {
      entry = std::min(a, b);
      face = ((ray.slope < 0) != mirrored) ? kFaceTop : kFaceBottom;
    }
    entry = std::max(entry, s_lo);
    if (entry > std::min(t_out, std::max(a, b))) continue;
    const bool better = entry < best.s || (entry == best.s && best.candidate >= 0 &&
                                           c.prism < candidates_[static_cast<size_t>(best.candidate)].prism);
    if (better) {
      best.s = entry;
      best.candidate = static_cast<int>(k);
      best.face = face;
    }
  }
}

namespace {

SolidPoint solid_point(const Prism& p, float lx, float ly, float z, Face face) {
  SolidPoint sp{&p, 0, 0, 0, 0, 0, z, p.material, false};
  switch (face) {
    case kFaceMinusX:
    case kFacePlusX: {
      const float sign = face == kFaceMinusX ? -1.0f : 1.0f;
      sp.nx = sign * p.cos_yaw;
      sp.ny = sign * p.sin_yaw;
      sp.u = ly;
      sp.v = z;
      break;
    }
    case kFaceMinusY:
    case kFacePlusY: {
      const float sign = face == kFaceMinusY ? -1.0f : 1.0f;
      sp.nx = -sign * p.sin_yaw;
      sp.ny = sign * p.cos_yaw;
      sp.u = lx;
      sp.v = z;
      break;
    }
    case kFaceRound: {
      const float inv_r = 1.0f / p.hx;
      sp.nx = lx * inv_r;
      sp.ny = ly * inv_r;
      sp.u = fast_atan2(ly, lx) * p.hx;
      sp.v = z;
      break;
    }
    case kFaceTop:
    case kFaceBottom:
      sp.nz = face == kFaceTop ? 1.0f : -1.0f;
      sp.u = lx;
      sp.v = ly;
      sp.material = p.top_material;
      break;
  }
  sp.u += p.u_offset;
  sp.v += p.v_offset;
  if (sp.nz == 0 && z < p.base_height) {
    sp.material = p.base_material;
    sp.base = true;
  }
  return sp;
}

}  // namespace

void Tracer::shade_solid(const Ray& ray, const Hit& hit, bool mirrored, float extra_blur, Shaded& out) const {
  const Candidate& c = candidates_[static_cast<size_t>(hit.candidate)];
  const Prism& p = scene_.prisms[c.prism];
  const float s = hit.s;
  const float dx = c.c * ray.ux - c.s * ray.uy, dy = c.s * ray.ux + c.c * ray.uy;
  const float zr = oz_ + ray.slope * s;
  const SolidPoint sp =
      solid_point(p, c.lox + s * dx, c.loy + s * dy, mirrored ? -zr : zr, static_cast<Face>(hit.face));
  const MaterialData& m = scene_.materials[sp.material];
  const float dz = mirrored ? -ray.slope : ray.slope;
  const float cos_i = std::abs(sp.nx * ray.wx + sp.ny * ray.wy + sp.nz * dz) * ray.inv_len;
  const float footprint = s * ray.len * rays_.pixel_angle() * approx_rsqrt(std::max(cos_i, 0.05f)) + extra_blur;
  const Rgbf albedo = m.texture->sample(sp.u, sp.v, footprint) * p.tint * m.diffuse_scale;
  Rgbf e = p.ambient +
           p.directional * std::max(0.0f, sp.nx * p.light_dir.x() + sp.ny * p.light_dir.y() + sp.nz * p.light_dir.z());
  if (scene_.sky.has_sun) {
    const Eigen::Vector3f& sun = scene_.sky.sun_dir;
    e += scene_.sky.sun_irradiance *
         (std::max(0.0f, sp.nx * sun.x() + sp.ny * sun.y() + sp.nz * sun.z()) * p.sun_visibility);
  }
  if (sp.nz == 0 && p.z0 < 0.05f && sp.z < 0.3f) {  // contact shade near the ground
    const float t = sp.z * (1.0f / 0.3f);
    e = e * (0.7f + 0.3f * t * (2.0f - t));
  }
  out.radiance = albedo * e + m.emission;
  out.depth = s;
  out.surface = sp.base ? GT::SURFACE_BASEBOARD : p.surface;
  out.phenomena = m.phenomena & (GT::PHENOMENON_TEXTURELESS | GT::PHENOMENON_REPETITIVE);
  if (sp.base) out.phenomena |= m.phenomena & GT::PHENOMENON_DARK_STRIPE;
}

inline const FloorFeature* Tracer::floor_feature(float x, float y, uint16_t& material) const {
  material = scene_.floor_material;
  const PlanGrid& g = scene_.grid;
  if (!g.inside(x, y)) return nullptr;
  const int cell = g.index(x, y);
  const uint32_t begin = g.feature_start[static_cast<size_t>(cell)],
                 end = g.feature_start[static_cast<size_t>(cell) + 1];
  if (begin == end) return nullptr;
  for (uint32_t k = end; k > begin; --k) {
    const FloorFeature& f = scene_.floor_features[g.features[k - 1]];
    if (!feature_contains(f, x, y)) continue;
    if (f.kind == FloorFeature::kPit) return &f;
    if (f.kind == FloorFeature::kPuddle) {
      const PuddleMask& mask = scene_.puddle_masks[static_cast<size_t>(f.mask)];
      float lx, ly;
      to_local(f, x, y, lx, ly);
      const float gx = (lx + f.hx) / mask.cell, gy = (ly + f.hy) / mask.cell;
      const int ix = std::clamp(static_cast<int>(gx), 0, mask.nx - 2),
                iy = std::clamp(static_cast<int>(gy), 0, mask.ny - 2);
      const float fx = gx - static_cast<float>(ix), fy = gy - static_cast<float>(iy);
      const float* row0 = mask.field.data() + static_cast<size_t>(iy) * mask.nx + ix;
      const float* row1 = row0 + mask.nx;
      const float v = (row0[0] * (1 - fx) + row0[1] * fx) * (1 - fy) + (row1[0] * (1 - fx) + row1[1] * fx) * fy;
      if (v <= 0) continue;
    }
    material = f.material;
    return nullptr;
  }
  return nullptr;
}

Rgbf Tracer::sky(float dx, float dy, float dz, float blur) const {
  const SkyData& sky = scene_.sky;
  const float t = std::sqrt(std::max(dz, 0.0f));
  Rgbf c = lerp(sky.horizon, sky.zenith, t);
  if (sky.has_sun) {
    const float cosang = dx * sky.sun_dir.x() + dy * sky.sun_dir.y() + dz * sky.sun_dir.z();
    const float w = std::max(sky.sun_radius, blur);
    const float lobe = std::exp((cosang - 1.0f) / (w * w));
    const float halo = std::exp((cosang - 1.0f) / 0.02f);
    c += sky.sun_irradiance * (lobe / (2.0f * static_cast<float>(M_PI) * w * w) + halo * 0.4f);
  }
  return c;
}

Rgbf Tracer::light_lobes(const Ray& ray, float x, float y, float roughness) const {
  // Microfacet highlight (Beckmann distribution of facet normals, slope rms m)
  // of small bright lamps: L = D(h) I / (4 d^2 cos(view)). Near grazing view
  // it stretches into the long streaks lamps make on wet ground.
  Rgbf sum(0.0f);
  const float m = std::max(roughness, 0.01f), inv_m2 = 1.0f / (m * m);
  const float vx = -ray.wx * ray.inv_len, vy = -ray.wy * ray.inv_len, vz = -ray.slope * ray.inv_len;  // to the camera
  for (uint32_t i : glare_lights_) {
    const PointLight& l = scene_.lights[i];
    const float lx = l.position.x() - x, ly = l.position.y() - y, lz = l.position.z();
    const float d2 = lx * lx + ly * ly + lz * lz, inv_d = 1.0f / std::sqrt(d2);
    const float hx = lx * inv_d + vx, hy = ly * inv_d + vy, hz = lz * inv_d + vz;
    const float h2 = hx * hx + hy * hy + hz * hz;
    const float cos2 = hz * hz / h2;  // cos^2 of the half vector to the floor normal
    const float tan2 = (1.0f - cos2) / cos2;
    if (tan2 * inv_m2 > 12.0f) continue;  // exp(-12): nothing to add
    const float d = std::exp(-tan2 * inv_m2) * inv_m2 / (static_cast<float>(M_PI) * cos2 * cos2);
    const float e = l.glare * (lz * inv_d);  // a downward emitter's intensity towards this point
    sum += Rgbf(1.0f, 0.85f, 0.65f) * (d * e / (4.0f * d2 * std::max(vz, 0.02f)));
  }
  return sum;
}

Rgbf Tracer::reflection(const Ray& ray, float s_floor, float roughness) const {
  // Mirror world: the ray goes on below the floor; the ceiling mirrors to z = -H.
  const float s_hi = scene_.has_ceiling ? (-scene_.ceiling_height - oz_) * ray.inv_slope : kInf;
  Hit hit;
  nearest(ray, s_floor, s_hi, true, hit);
  const float pa = rays_.pixel_angle();
  const float s = hit.candidate >= 0 ? hit.s : s_hi;
  const float blur = 2.0f * roughness * (s - s_floor) * ray.len;
  if (hit.candidate >= 0) {
    Shaded sh;
    shade_solid(ray, hit, true, blur, sh);
    return sh.radiance;
  }
  if (scene_.has_ceiling) {
    const float x = ox_ + s_hi * ray.wx, y = oy_ + s_hi * ray.wy;
    return scene_.ceiling_radiance.sample(x, y, s_hi * ray.len * pa + blur);
  }
  return sky(ray.wx * ray.inv_len, ray.wy * ray.inv_len, -ray.slope * ray.inv_len, roughness + pa);
}

void Tracer::shade_pit(const Ray& ray, const FloorFeature& pit, float s_floor, Shaded& out) const {
  float lox, loy, dx, dy;
  to_local(pit, ox_, oy_, lox, loy);
  dir_to_local(pit, ray.wx, ray.wy, dx, dy);
  float t_out;
  if (pit.ellipse) {
    const float ex = lox / pit.hx, ey = loy / pit.hy, dex = dx / pit.hx, dey = dy / pit.hy;
    const float a = dex * dex + dey * dey, b = ex * dex + ey * dey, c = ex * ex + ey * ey - 1.0f;
    t_out = (-b + std::sqrt(std::max(0.0f, b * b - a * c))) / a;
  } else {
    float t_in;
    Face face;
    rect_interval(lox, loy, dx, dy, pit.hx, pit.hy, t_in, t_out, face);
  }
  t_out = std::max(t_out, s_floor);
  const float z_exit = oz_ + ray.slope * t_out;
  float s, u, v, z;
  if (z_exit >= -pit.depth) {  // the far wall of the pit
    s = t_out;
    z = z_exit;
    u = (lox + s * dx) + (loy + s * dy);
    v = z;
  } else {  // its bottom
    s = (-pit.depth - oz_) * ray.inv_slope;
    z = -pit.depth;
    u = ox_ + s * ray.wx;
    v = oy_ + s * ray.wy;
  }
  const MaterialData& m = scene_.materials[pit.material];
  const float footprint = s * ray.len * rays_.pixel_angle() * 2.0f;
  const Rgbf albedo = m.texture->sample(u, v, footprint);
  const float shade = 0.25f + 0.75f * std::exp(z / 0.25f);  // darker deeper down
  out.radiance = albedo * (scene_.pit_irradiance * shade);
  out.depth = s;
  out.specular = 0;
  out.surface = GT::SURFACE_PIT;
  out.phenomena = 0;
}

void Tracer::finish_floor(const FloorSample& f, Shaded& out, float& fresnel, float& roughness) const {
  const PixelRay& pr = rays_.ray(f.pixel);
  const MaterialData& m = scene_.materials[f.material];
  const Rgbf albedo = m.texture->sample(f.x, f.y, pr.floor_footprint) * m.diffuse_scale;
  const Rgbf e =
      scene_.floor_irradiance.empty() ? scene_.floor_irradiance_outside : scene_.floor_irradiance.sample(f.x, f.y);
  out.radiance = albedo * e;
  out.depth = pr.s_floor * pr.planar;
  out.specular = 0;
  out.surface = GT::SURFACE_FLOOR;
  out.phenomena = m.phenomena & (GT::PHENOMENON_TEXTURELESS | GT::PHENOMENON_REPETITIVE);
  fresnel = 0;
  if (m.f0 > 0) {
    const float cos_i = -pr.slope * pr.inv_len;
    fresnel = m.f0 + (1.0f - m.f0) * pow5(1.0f - cos_i);
    roughness = m.roughness;
  }
}

Rgbf Tracer::floor_reflection(int pixel, float roughness) const {
  const PixelRay& pr = rays_.ray(pixel);
  const Ray ray = make_ray(pr);
  float x, y;
  floor_point(pr, x, y);
  Rgbf r = reflection(ray, pr.s_floor, roughness);
  if (!glare_lights_.empty()) r += light_lobes(ray, x, y, roughness);
  return r;
}

inline void Tracer::add_reflection(Shaded& out, float fresnel, const Rgbf& reflected) {
  const Rgbf specular = reflected * fresnel;
  out.radiance = out.radiance * (1.0f - fresnel) + specular;
  out.specular = specular.luminance();
  if (out.specular > 0.35f * out.radiance.luminance()) out.phenomena |= GT::PHENOMENON_REFLECTION;
}

// Inline: called once per pixel, and out of line it cost 18 % of a frame's render time.
inline Tracer::Hit Tracer::first_solid(const PixelRay& pr, const Ray& ray, float& s_reach) const {
  s_reach = pr.slope > 0 && scene_.has_ceiling ? s_ceiling_up_ * ray.inv_slope : pr.s_floor;
  Hit hit;
  if (bin_may_hit(ray, s_reach)) nearest(ray, 0.0f, s_reach, false, hit);
  return hit;
}

bool Tracer::shade_primary(int pixel, Shaded& out, float& fresnel, FloorSample* floor) const {
  const PixelRay& pr = rays_.ray(pixel);
  const Ray ray = make_ray(pr);
  const bool up = pr.slope > 0;
  float s_hi;
  const Hit hit = first_solid(pr, ray, s_hi);
  fresnel = 0;
  if (hit.candidate >= 0) {
    shade_solid(ray, hit, false, 0.0f, out);
    out.specular = 0;
  } else if (!up) {
    FloorSample f;
    f.pixel = pixel;
    floor_point(pr, f.x, f.y);
    if (const FloorFeature* pit = floor_feature(f.x, f.y, f.material)) {
      shade_pit(ray, *pit, pr.s_floor, out);
    } else {
      *floor = f;
      return true;
    }
  } else if (scene_.has_ceiling) {
    const float x = ox_ + s_hi * ray.wx, y = oy_ + s_hi * ray.wy;
    out.radiance = scene_.ceiling_radiance.sample(x, y, s_hi * ray.len * rays_.pixel_angle());
    out.depth = s_hi;
    out.specular = 0;
    out.surface = GT::SURFACE_CEILING;
    out.phenomena = 0;
  } else {
    out.radiance = sky(ray.wx * ray.inv_len, ray.wy * ray.inv_len, ray.slope * ray.inv_len, rays_.pixel_angle());
    out.depth = kInf;
    out.specular = 0;
    out.surface = GT::SURFACE_SKY;
    out.phenomena = 0;
    return false;
  }
  out.depth *= pr.planar;
  return false;
}

namespace {

// Spacing of the lattice on which a floor pixel's reflection is traced: a
// rough surface blurs its mirror image over roughness x focal length pixels
// (times the fraction of the path beyond the floor), so it can be sampled
// sparsely and interpolated; a still water surface is traced at every pixel.
int reflection_step(float fresnel, float roughness) {
  if (fresnel <= 0) return 0;
  if (roughness >= 0.01f) return 4;  // polished stone and rougher: >= 6 px of blur far out
  if (roughness >= 0.005f) return 2;
  return 1;  // still water
}

}  // namespace

void Tracer::shade_image(Shaded* out, const std::function<void(int, int)>& rows_done) const {
  const int width = rays_.width(), height = rays_.height();
  const size_t n = static_cast<size_t>(width) * height;
  // Scratch reused across frames (no page faults, no clearing): every entry
  // read below is written first in this call.
  thread_local std::vector<float> fresnel, roughness;
  thread_local std::vector<Rgbf> reflected;
  thread_local std::vector<uint8_t> step;
  thread_local std::vector<FloorSample> floor;
  fresnel.resize(n);
  roughness.resize(n);
  reflected.resize(n);
  step.resize(n);
  floor.resize(static_cast<size_t>(width) * kBandRows);
  // The image goes in bands of rows through three passes; a band's later
  // passes run while what its earlier ones wrote is still in cache. Pass 2
  // of band k reads the lattice spacing of the next band's first row and
  // pass 3 its traced reflections, so the passes run two bands apart.
  const int num_bands = (height + kBandRows - 1) / kBandRows;
  auto rows = [&](int band) { return std::make_pair(band * kBandRows, std::min(height, (band + 1) * kBandRows)); };
  for (int k = 0; k < num_bands + 2; ++k) {
    if (k < num_bands) {
      const auto [y0, y1] = rows(k);
      shade_band(y0, y1, out, fresnel.data(), roughness.data(), step.data(), floor.data());
    }
    if (k >= 1 && k - 1 < num_bands) {
      const auto [y0, y1] = rows(k - 1);
      trace_reflections(y0, y1, step.data(), roughness.data(), reflected.data());
    }
    if (k >= 2) {
      const auto [y0, y1] = rows(k - 2);
      blend_reflections(y0, y1, step.data(), fresnel.data(), reflected.data(), out);
      rows_done(y0, y1);
    }
  }
}

void Tracer::shade_band(int y0, int y1, Shaded* out, float* fresnel, float* roughness, uint8_t* step,
                        FloorSample* floor) const {
  const int width = rays_.width();
  const size_t begin = static_cast<size_t>(y0) * width, end = static_cast<size_t>(y1) * width;
  size_t floor_count = 0;
  for (size_t i = begin; i < end; ++i)
    floor_count += shade_primary(static_cast<int>(i), out[i], fresnel[i], &floor[floor_count]);
  for (size_t k = 0; k < floor_count; ++k) {
    const size_t i = static_cast<size_t>(floor[k].pixel);
    finish_floor(floor[k], out[i], fresnel[i], roughness[i]);
  }
  for (size_t i = begin; i < end; ++i) step[i] = static_cast<uint8_t>(reflection_step(fresnel[i], roughness[i]));
}

// A pixel off its lattice, inside a lattice cell whose four corners share
// its spacing, takes its reflection from those corners.
inline bool Tracer::interpolated(const uint8_t* step, int x, int y) const {
  const int width = rays_.width(), height = rays_.height();
  const int s = step[static_cast<size_t>(y) * width + x] & 0x7f, m = s - 1;  // s is 1, 2 or 4
  if (s < 2 || ((x | y) & m) == 0) return false;
  const int x0 = x & ~m, y0 = y & ~m, x1 = x0 + s, y1 = y0 + s;
  if (x1 >= width || y1 >= height) return false;
  auto same = [&](int xx, int yy) { return (step[static_cast<size_t>(yy) * width + xx] & 0x7f) == s; };
  return same(x0, y0) && same(x1, y0) && same(x0, y1) && same(x1, y1);
}

// step[i] becomes 0: no reflection, 1: traced here, 2+ with the top bit: interpolated.
void Tracer::trace_reflections(int y0, int y1, uint8_t* step, const float* roughness, Rgbf* reflected) const {
  const int width = rays_.width();
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      if (!step[i]) continue;
      if (interpolated(step, x, y)) {
        step[i] |= 0x80;
        continue;
      }
      reflected[i] = floor_reflection(static_cast<int>(i), roughness[i]);
    }
}

void Tracer::blend_reflections(int y0, int y1, const uint8_t* step, const float* fresnel, const Rgbf* reflected,
                               Shaded* out) const {
  const int width = rays_.width();
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      if (!step[i]) continue;
      if (!(step[i] & 0x80)) {
        add_reflection(out[i], fresnel[i], reflected[i]);
        continue;
      }
      const int s = step[i] & 0x7f, x0 = x & ~(s - 1), ys = y & ~(s - 1);
      const float inv_s = 1.0f / static_cast<float>(s);  // exact: s is a power of two
      const float fx = static_cast<float>(x - x0) * inv_s, fy = static_cast<float>(y - ys) * inv_s;
      const size_t a = static_cast<size_t>(ys) * width + x0, b = a + static_cast<size_t>(s) * width;
      add_reflection(out[i], fresnel[i],
                     lerp(lerp(reflected[a], reflected[a + s], fx), lerp(reflected[b], reflected[b + s], fx), fy));
    }
}

Ranged Tracer::range(int pixel) const {
  const PixelRay& pr = rays_.ray(pixel);
  const Ray ray = make_ray(pr);
  const bool up = pr.slope > 0;
  float s_hi;
  const Hit hit = first_solid(pr, ray, s_hi);
  const SkyData& sky = scene_.sky;
  const float sun_strength = sky.has_sun ? sky.sun_irradiance.luminance() / 300.0f : 0.0f;
  Ranged out;
  if (hit.candidate >= 0) {
    const Candidate& c = candidates_[static_cast<size_t>(hit.candidate)];
    const Prism& p = scene_.prisms[c.prism];
    const float dx = c.c * ray.ux - c.s * ray.uy, dy = c.s * ray.ux + c.c * ray.uy;
    const SolidPoint sp =
        solid_point(p, c.lox + hit.s * dx, c.loy + hit.s * dy, oz_ + ray.slope * hit.s, static_cast<Face>(hit.face));
    const MaterialData& m = scene_.materials[sp.material];
    const float cos_i = std::abs(sp.nx * ray.wx + sp.ny * ray.wy + sp.nz * ray.slope) * ray.inv_len;
    out.depth = hit.s * pr.planar;
    out.ir_return = m.ir_albedo * cos_i;
    if (sky.has_sun)
      out.sunlit = sun_strength * p.sun_visibility *
                   std::max(0.0f, sp.nx * sky.sun_dir.x() + sp.ny * sky.sun_dir.y() + sp.nz * sky.sun_dir.z());
    return out;
  }
  if (!up) {
    float x, y;
    floor_point(pr, x, y);
    uint16_t mid;
    if (const FloorFeature* pit = floor_feature(x, y, mid)) {
      Shaded sh;
      shade_pit(ray, *pit, pr.s_floor, sh);
      out.depth = sh.depth * pr.planar;
      out.ir_return = scene_.materials[pit->material].ir_albedo * 0.7f;
      return out;
    }
    const MaterialData& m = scene_.materials[mid];
    const float cos_i = -ray.slope * ray.inv_len;
    out.depth = pr.s_floor * pr.planar;
    out.ir_return = m.ir_albedo * cos_i;
    out.specular = m.f0 * std::max(0.0f, 1.0f - m.roughness / 0.03f);  // only smooth surfaces lose the pattern
    if (sky.has_sun) out.sunlit = sun_strength * sky.sun_dir.z() * scene_.floor_sunlit.sample(x, y, 1.0f);
    return out;
  }
  if (scene_.has_ceiling) {
    out.depth = s_hi * pr.planar;
    out.ir_return = 0.6f * ray.slope * ray.inv_len;
    return out;
  }
  out.depth = kInf;
  return out;
}

}  // namespace ivoa::sim::detail
