#pragma once
// Exact 2-D geometry of footprints (oriented rectangles, circles, ellipses):
// ray intervals and distances, shared by the renderer, lighting and queries.
#include <algorithm>
#include <cmath>
#include <limits>

#include "scene_data.hpp"

namespace ivoa::sim::detail {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Which side of a footprint a ray entered through.
enum Face : uint8_t { kFaceMinusX, kFacePlusX, kFaceMinusY, kFacePlusY, kFaceRound, kFaceTop, kFaceBottom };

// Interval [t_in, t_out] of a 2-D ray (origin o, unit direction d) inside a
// rectangle centred at the origin of its frame with half extents (hx, hy);
// o and d already in that frame. Empty if t_in > t_out.
inline void rect_interval(float ox, float oy, float dx, float dy, float hx, float hy, float& t_in, float& t_out,
                          Face& face) {
  float tx0, tx1, ty0, ty1;
  Face fx, fy;
  if (std::abs(dx) < 1e-12f) {
    if (std::abs(ox) > hx) {
      t_in = kInf;
      t_out = -kInf;
      return;
    }
    tx0 = -kInf;
    tx1 = kInf;
    fx = kFaceMinusX;
  } else {
    const float inv = 1.0f / dx;
    const float a = (-hx - ox) * inv, b = (hx - ox) * inv;
    tx0 = std::min(a, b);
    tx1 = std::max(a, b);
    fx = dx > 0 ? kFaceMinusX : kFacePlusX;
  }
  if (std::abs(dy) < 1e-12f) {
    if (std::abs(oy) > hy) {
      t_in = kInf;
      t_out = -kInf;
      return;
    }
    ty0 = -kInf;
    ty1 = kInf;
    fy = kFaceMinusY;
  } else {
    const float inv = 1.0f / dy;
    const float a = (-hy - oy) * inv, b = (hy - oy) * inv;
    ty0 = std::min(a, b);
    ty1 = std::max(a, b);
    fy = dy > 0 ? kFaceMinusY : kFacePlusY;
  }
  if (tx0 > ty0) {
    t_in = tx0;
    face = fx;
  } else {
    t_in = ty0;
    face = fy;
  }
  t_out = std::min(tx1, ty1);
}

// Interval of a 2-D ray inside a circle of radius r centred at c; o - c = (ox, oy).
inline void circle_interval(float ox, float oy, float dx, float dy, float r, float& t_in, float& t_out) {
  const float b = ox * dx + oy * dy;
  const float c = ox * ox + oy * oy - r * r;
  const float disc = b * b - c;
  if (disc < 0) {
    t_in = kInf;
    t_out = -kInf;
    return;
  }
  const float s = std::sqrt(disc);
  t_in = -b - s;
  t_out = -b + s;
}

// World point / direction into a prism's (or feature's) local frame.
template <class Shape>
inline void to_local(const Shape& p, float x, float y, float& lx, float& ly) {
  const float dx = x - p.cx, dy = y - p.cy;
  lx = p.cos_yaw * dx + p.sin_yaw * dy;
  ly = -p.sin_yaw * dx + p.cos_yaw * dy;
}
template <class Shape>
inline void dir_to_local(const Shape& p, float dx, float dy, float& lx, float& ly) {
  lx = p.cos_yaw * dx + p.sin_yaw * dy;
  ly = -p.sin_yaw * dx + p.cos_yaw * dy;
}

// Interval of a world 2-D ray inside a prism footprint.
inline void footprint_interval(const Prism& p, float ox, float oy, float dx, float dy, float& t_in, float& t_out,
                               Face& face) {
  if (p.shape == Prism::kCircle) {
    circle_interval(ox - p.cx, oy - p.cy, dx, dy, p.hx, t_in, t_out);
    face = kFaceRound;
    return;
  }
  float lox, loy, ldx, ldy;
  to_local(p, ox, oy, lox, loy);
  dir_to_local(p, dx, dy, ldx, ldy);
  rect_interval(lox, loy, ldx, ldy, p.hx, p.hy, t_in, t_out, face);
}

// Signed distance from a world point to a prism footprint (negative inside).
inline double footprint_distance(const Prism& p, double x, double y) {
  if (p.shape == Prism::kCircle) return std::hypot(x - p.cx, y - p.cy) - p.hx;
  const double dx = x - p.cx, dy = y - p.cy;
  const double lx = std::abs(p.cos_yaw * dx + p.sin_yaw * dy) - p.hx;
  const double ly = std::abs(-p.sin_yaw * dx + p.cos_yaw * dy) - p.hy;
  const double outside = std::hypot(std::max(lx, 0.0), std::max(ly, 0.0));
  return outside > 0 ? outside : std::max(lx, ly);
}

// Is a world point inside a floor feature's outline (rect or ellipse)?
inline bool feature_contains(const FloorFeature& f, float x, float y) {
  float lx, ly;
  to_local(f, x, y, lx, ly);
  if (f.ellipse) {
    const float a = lx / f.hx, b = ly / f.hy;
    return a * a + b * b <= 1.0f;
  }
  return std::abs(lx) <= f.hx && std::abs(ly) <= f.hy;
}

// Signed distance from a world point to a feature's outline (negative inside).
double feature_distance(const FloorFeature& f, double x, double y);

}  // namespace ivoa::sim::detail
