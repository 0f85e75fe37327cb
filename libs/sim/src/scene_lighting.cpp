// Precomputed lighting: the scene is static, so irradiance is computed once
// per scene: per prism (ambient + one dominant direction + sun visibility)
// and per 10 cm of floor (contact shadows, shade under furniture, pools of
// light under lamps, sun shadows).
#include <algorithm>
#include <cmath>

#include "geometry.hpp"
#include "scene_data.hpp"

namespace ivoa::sim::detail {
namespace {

// Does a 3-D ray from p towards `dir` (unit) hit any prism other than `skip`?
bool occluded(const SceneData& s, const Eigen::Vector3f& p, const Eigen::Vector3f& dir, size_t skip) {
  const float h = std::hypot(dir.x(), dir.y());
  if (h < 1e-6f) return false;
  const float ux = dir.x() / h, uy = dir.y() / h, slope = dir.z() / h;
  for (size_t i = 0; i < s.prisms.size(); ++i) {
    if (i == skip) continue;
    const Prism& q = s.prisms[i];
    float t_in, t_out;
    Face face;
    footprint_interval(q, p.x(), p.y(), ux, uy, t_in, t_out, face);
    if (t_out < 1e-3f || t_in > t_out) continue;
    t_in = std::max(t_in, 1e-3f);
    // z along the ray rises with slope; overlap of [t_in, t_out] with the prism's z slab.
    const float za = p.z() + slope * t_in, zb = p.z() + slope * t_out;
    if (std::max(za, zb) >= q.z0 && std::min(za, zb) <= q.z1) return true;
  }
  return false;
}

// From a prism's centre to just outside its face that looks most towards the sun.
Eigen::Vector2f sunward_offset(const Prism& p, const Eigen::Vector2f& sun) {
  if (p.shape == Prism::kCircle) return sun * (p.hx + 0.02f);
  const Eigen::Vector2f ax(p.cos_yaw, p.sin_yaw), ay(-p.sin_yaw, p.cos_yaw);
  const float sx = ax.dot(sun), sy = ay.dot(sun);
  if (std::abs(sx) * p.hy > std::abs(sy) * p.hx) return ax * ((sx > 0 ? 1.0f : -1.0f) * (p.hx + 0.02f));
  return ay * ((sy > 0 ? 1.0f : -1.0f) * (p.hy + 0.02f));
}

void light_prisms(SceneData& s) {
  const bool indoor = s.environment == Environment::kIndoor;
  for (size_t i = 0; i < s.prisms.size(); ++i) {
    Prism& p = s.prisms[i];
    const float zc = std::clamp(0.5f * (p.z0 + p.z1), p.z0, std::min(p.z1, p.z0 + 1.5f));
    const Eigen::Vector3f c(p.cx, p.cy, zc);
    Eigen::Vector3f vec = Eigen::Vector3f::Zero();
    Rgbf sum(0.0f);
    float total = 0;
    for (const PointLight& l : s.lights) {
      const Eigen::Vector3f to = l.position - c;
      const float d2 = std::max(0.04f, to.squaredNorm()), d = std::sqrt(d2);
      const float cos_e = l.downward ? std::max(0.0f, to.z() / d) : 1.0f;
      const float w = cos_e / d2;
      if (w <= 0) continue;
      const Rgbf e = l.intensity * w;
      sum += e;
      vec += (to / d) * e.luminance();
      total += e.luminance();
    }
    const float coherence = total > 0 ? vec.norm() / total : 0.0f;  // 1 = all light from one direction
    p.light_dir = vec.norm() > 0 ? Eigen::Vector3f(vec.normalized()) : Eigen::Vector3f(0, 0, 1);
    p.directional = sum * coherence;
    p.ambient = s.ambient * (indoor ? 0.85f : 0.6f) + sum * ((1.0f - coherence) * 0.5f);
    if (s.sky.has_sun) {
      const Eigen::Vector3f& sun = s.sky.sun_dir;
      const Eigen::Vector2f toward = sunward_offset(p, Eigen::Vector2f(sun.x(), sun.y()).normalized());
      int lit = 0;
      const float zs[3] = {p.z0 + 0.15f * (p.z1 - p.z0), 0.5f * (p.z0 + p.z1), p.z0 + 0.85f * (p.z1 - p.z0)};
      for (float z : zs) lit += !occluded(s, Eigen::Vector3f(p.cx + toward.x(), p.cy + toward.y(), z), sun, i);
      p.sun_visibility = static_cast<float>(lit) / 3.0f;
    }
  }
}

struct FloorGrid {
  float x0, y0, cell;
  int nx, ny;
  Eigen::Vector2f centre(int i, int j) const {
    return {x0 + (static_cast<float>(i) + 0.5f) * cell, y0 + (static_cast<float>(j) + 0.5f) * cell};
  }
};

FloorGrid floor_grid_for(const SceneData& s) {
  Eigen::AlignedBox2d box = s.bounds;
  box.extend(box.min() - Eigen::Vector2d(2, 2));
  box.extend(box.max() + Eigen::Vector2d(2, 2));
  const float w = static_cast<float>(box.sizes().x()), h = static_cast<float>(box.sizes().y());
  const float cell = std::max(0.1f, std::max(w, h) / 1024.0f);
  return {static_cast<float>(box.min().x()), static_cast<float>(box.min().y()), cell,
          static_cast<int>(std::ceil(w / cell)), static_cast<int>(std::ceil(h / cell))};
}

// 1 where the sun reaches the ground, 0 in a shadow: each prism darkens the
// ground points whose ray to the sun passes through it.
std::vector<float> sun_visibility(const SceneData& s, const FloorGrid& g) {
  std::vector<float> vis(static_cast<size_t>(g.nx) * g.ny, 1.0f);
  if (!s.sky.has_sun) return vis;
  const Eigen::Vector3f& sun = s.sky.sun_dir;
  const float h = std::hypot(sun.x(), sun.y());
  if (h < 1e-4f) return vis;
  const float ux = sun.x() / h, uy = sun.y() / h, tan_e = sun.z() / h;
  for (const Prism& p : s.prisms) {
    const float r = p.radius(), reach = p.z1 / tan_e;
    const float xa = std::min(p.cx - r, p.cx - r - ux * reach), xb = std::max(p.cx + r, p.cx + r - ux * reach);
    const float ya = std::min(p.cy - r, p.cy - r - uy * reach), yb = std::max(p.cy + r, p.cy + r - uy * reach);
    const int i0 = std::max(0, static_cast<int>((xa - g.x0) / g.cell)),
              i1 = std::min(g.nx - 1, static_cast<int>((xb - g.x0) / g.cell));
    const int j0 = std::max(0, static_cast<int>((ya - g.y0) / g.cell)),
              j1 = std::min(g.ny - 1, static_cast<int>((yb - g.y0) / g.cell));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        float& v = vis[static_cast<size_t>(j) * g.nx + i];
        if (v == 0) continue;
        const Eigen::Vector2f c = g.centre(i, j);
        float t_in, t_out;
        Face face;
        footprint_interval(p, c.x(), c.y(), ux, uy, t_in, t_out, face);
        const float s0 = p.z0 / tan_e, s1 = p.z1 / tan_e;
        if (t_out >= 0 && std::max(t_in, s0) <= std::min(t_out, s1)) v = 0;
      }
  }
  return vis;
}

void light_floor(SceneData& s) {
  const FloorGrid g = floor_grid_for(s);
  const size_t n = static_cast<size_t>(g.nx) * g.ny;
  std::vector<float> ao(n, 1.0f), under(n, 1.0f);
  // Contact shadows next to standing solids and shade under floating ones.
  for (const Prism& p : s.prisms) {
    const bool standing = p.z0 < 0.05f;
    const float reach = standing ? 0.45f : 0.0f, r = p.radius() + reach;
    const int i0 = std::max(0, static_cast<int>((p.cx - r - g.x0) / g.cell)),
              i1 = std::min(g.nx - 1, static_cast<int>((p.cx + r - g.x0) / g.cell));
    const int j0 = std::max(0, static_cast<int>((p.cy - r - g.y0) / g.cell)),
              j1 = std::min(g.ny - 1, static_cast<int>((p.cy + r - g.y0) / g.cell));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2f c = g.centre(i, j);
        const float d = static_cast<float>(footprint_distance(p, c.x(), c.y()));
        const size_t k = static_cast<size_t>(j) * g.nx + i;
        if (standing) ao[k] = std::min(ao[k], 1.0f - 0.45f * std::exp(-std::max(0.0f, d) / 0.1f));
        else if (d <= 0) under[k] = std::min(under[k], 1.0f - 0.6f * std::exp(-p.z0 / 0.6f));
      }
  }
  const std::vector<float> sunlit = sun_visibility(s, g);
  const float sun_e = s.sky.has_sun ? s.sky.sun_dir.z() : 0.0f;
  std::vector<Rgbf> e(n);
  for (size_t k = 0; k < n; ++k) e[k] = s.ambient * (ao[k] * under[k]) + s.sky.sun_irradiance * (sun_e * sunlit[k]);
  for (const PointLight& l : s.lights) {
    const float reach = std::max(3.0f, 3.0f * l.position.z());
    const int i0 = std::max(0, static_cast<int>((l.position.x() - reach - g.x0) / g.cell));
    const int i1 = std::min(g.nx - 1, static_cast<int>((l.position.x() + reach - g.x0) / g.cell));
    const int j0 = std::max(0, static_cast<int>((l.position.y() - reach - g.y0) / g.cell));
    const int j1 = std::min(g.ny - 1, static_cast<int>((l.position.y() + reach - g.y0) / g.cell));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2f c = g.centre(i, j);
        const float dx = l.position.x() - c.x(), dy = l.position.y() - c.y(), z = l.position.z();
        const float d2 = dx * dx + dy * dy + z * z;
        const float cos_r = z / std::sqrt(d2);
        const float w = (l.downward ? cos_r * cos_r : cos_r) / d2;
        const size_t k = static_cast<size_t>(j) * g.nx + i;
        e[k] += l.intensity * (w * under[k] * (0.6f + 0.4f * ao[k]));
      }
  }
  s.floor_irradiance = RadianceMap(g.x0, g.y0, g.cell, g.nx, g.ny, std::move(e), 1);
  s.floor_sunlit = ScalarMap(g.x0, g.y0, g.cell, g.nx, g.ny, sunlit);
  s.floor_irradiance_outside = s.ambient + s.sky.sun_irradiance * sun_e;
  s.pit_irradiance = s.ambient * 0.35f;
}

}  // namespace

void compute_lighting(SceneData& s) {
  light_prisms(s);
  light_floor(s);
}

}  // namespace ivoa::sim::detail
