#pragma once
// Linear RGB radiance / albedo triples used inside the renderer.
#include <cmath>

#include "ivoa/sim/material.hpp"

namespace ivoa::sim {

struct Rgbf {
  float r = 0, g = 0, b = 0;
  Rgbf() = default;
  constexpr Rgbf(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  explicit constexpr Rgbf(float v) : r(v), g(v), b(v) {}
  Rgbf operator+(const Rgbf& o) const { return {r + o.r, g + o.g, b + o.b}; }
  Rgbf operator-(const Rgbf& o) const { return {r - o.r, g - o.g, b - o.b}; }
  Rgbf operator*(const Rgbf& o) const { return {r * o.r, g * o.g, b * o.b}; }
  Rgbf operator*(float s) const { return {r * s, g * s, b * s}; }
  Rgbf& operator+=(const Rgbf& o) {
    r += o.r;
    g += o.g;
    b += o.b;
    return *this;
  }
  float luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }
};

inline Rgbf lerp(const Rgbf& a, const Rgbf& b, float t) { return a + (b - a) * t; }

inline float srgb_to_linear(double c) {
  c = c < 0 ? 0 : (c > 1 ? 1 : c);
  return static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

inline Rgbf to_linear(const Rgb& c) { return {srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2])}; }

}  // namespace ivoa::sim
