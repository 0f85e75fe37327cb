#pragma once
// Tileable, mip-mapped albedo maps. Textures are synthesised once per scene
// (texture_synthesis.cpp); rendering only samples them, bilinearly, at the
// mip level that matches the pixel's footprint, so distant surfaces average
// their texture instead of aliasing.
#include <cstdint>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "color.hpp"

namespace ivoa::sim {

// floor(log2(x)) for a positive normal float, from its exponent bits.
inline int floor_log2(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return static_cast<int>((bits >> 23) & 0xff) - 127;
}

// A uint32 array in 2 MB pages where the kernel allows it: textures are
// read in scattered patterns and 4 KB pages thrash the TLB.
class HugeBuffer {
 public:
  HugeBuffer() = default;
  explicit HugeBuffer(size_t n);
  HugeBuffer(const HugeBuffer&) = delete;
  HugeBuffer& operator=(const HugeBuffer&) = delete;
  HugeBuffer(HugeBuffer&& o) noexcept : data_(o.data_), size_(o.size_) { o.data_ = nullptr, o.size_ = 0; }
  HugeBuffer& operator=(HugeBuffer&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    return *this;
  }
  ~HugeBuffer();
  uint32_t* data() { return data_; }
  const uint32_t* data() const { return data_; }
  size_t size() const { return size_; }
  uint32_t& operator[](size_t i) { return data_[i]; }

 private:
  uint32_t* data_ = nullptr;
  size_t size_ = 0;
};

class Texture {
 public:
  // `linear` is size x size linear RGB (row-major, v rows, u columns); size a power of two.
  Texture(int size, double texel_m, const std::vector<Rgbf>& linear);

  // Albedo at (u, v) metres for a pixel covering `footprint` metres of the surface.
  Rgbf sample(float u, float v, float footprint) const {
    int level = floor_log2(footprint * lod_scale_ + 1e-30f);
    level = level < 0 ? 0 : (level >= levels_ ? levels_ - 1 : level);
    const Level& lv = level_[level];
    const float x = u * lv.scale - 0.5f, y = v * lv.scale - 0.5f;
    // Round-to-nearest of (x - 0.5): floor(x), or one less at an exact
    // integer, where the interpolation gives the same value either way.
    const int x0 = round_to_int(x - 0.5f), y0 = round_to_int(y - 0.5f);
    const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
    // Each level carries a copy of its first column and row after the last,
    // so the 2 x 2 neighbourhood never wraps.
    const uint32_t* t = lv.texels + (y0 & lv.mask) * lv.stride + (x0 & lv.mask);
    const uint32_t t00 = t[0], t10 = t[1], t01 = t[lv.stride], t11 = t[lv.stride + 1];
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
#if defined(__SSE2__)
    const __m128i packed =
        _mm_set_epi32(static_cast<int>(t11), static_cast<int>(t01), static_cast<int>(t10), static_cast<int>(t00));
    const __m128i zero = _mm_setzero_si128();
    const __m128i lo = _mm_unpacklo_epi8(packed, zero), hi = _mm_unpackhi_epi8(packed, zero);
    __m128 c = _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(lo, zero)), _mm_set1_ps(w00));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(lo, zero)), _mm_set1_ps(w10)));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(hi, zero)), _mm_set1_ps(w01)));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(hi, zero)), _mm_set1_ps(w11)));
    c = _mm_mul_ps(_mm_mul_ps(c, c), _mm_set1_ps(1.0f / (255.0f * 255.0f)));
    alignas(16) float out[4];
    _mm_store_ps(out, c);
    return {out[0], out[1], out[2]};
#else
    auto channel = [&](int shift) {
      const float c = w00 * static_cast<float>((t00 >> shift) & 0xff) +
                      w10 * static_cast<float>((t10 >> shift) & 0xff) +
                      w01 * static_cast<float>((t01 >> shift) & 0xff) + w11 * static_cast<float>((t11 >> shift) & 0xff);
      return c * c * (1.0f / (255.0f * 255.0f));
    };
    return {channel(0), channel(8), channel(16)};
#endif
  }

  double period() const { return size_ / inv_texel_; }  // metres before the map repeats

  static int round_to_int(float x) {
#if defined(__SSE2__)
    return _mm_cvtss_si32(_mm_set_ss(x));
#else
    return static_cast<int>(std::nearbyint(x));
#endif
  }
  Rgbf mean() const { return mean_; }

 private:
  struct Level {
    const uint32_t* texels = nullptr;  // (side + 1) x (side + 1), the last row and column repeat the first
    float scale = 1;                   // texels per metre
    int mask = 0;                      // side - 1
    int stride = 1;                    // side + 1
  };
  int size_ = 0, levels_ = 0;  // levels down to 1 x 1 texel
  float inv_texel_ = 1, lod_scale_ = 1;
  Level level_[16];
  Rgbf mean_;
  HugeBuffer data_;  // all levels; texel = sqrt(linear) * 255 per channel (gamma 2)
};

// Linear-RGB image with metric placement, bilinear and clamped at the edges,
// with box-filtered mip levels: used for light maps and the ceiling's radiance.
class RadianceMap {
 public:
  RadianceMap() = default;
  RadianceMap(float x0, float y0, float cell, int nx, int ny, std::vector<Rgbf> values, int levels = 1);
  // Bilinear at the level matching `footprint` (0: finest), clamped at the edges.
  Rgbf sample(float x, float y, float footprint = 0) const {
    int l = 0;
    if (footprint > levels_[0].cell) {
      l = floor_log2(footprint / levels_[0].cell);
      if (l >= static_cast<int>(levels_.size())) l = static_cast<int>(levels_.size()) - 1;
    }
    const Level& lv = levels_[static_cast<size_t>(l)];
    float gx = (x - x0_) * lv.inv_cell - 0.5f, gy = (y - y0_) * lv.inv_cell - 0.5f;
    gx = gx < 0 ? 0 : (gx > lv.max_x ? lv.max_x : gx);
    gy = gy < 0 ? 0 : (gy > lv.max_y ? lv.max_y : gy);
    const int ix = static_cast<int>(gx), iy = static_cast<int>(gy);
    const float fx = gx - static_cast<float>(ix), fy = gy - static_cast<float>(iy);
    const Rgbf* v = lv.v.data() + static_cast<size_t>(iy) * lv.stride + ix;
    const Rgbf a = lerp(v[0], v[1], fx), b = lerp(v[lv.stride], v[lv.stride + 1], fx);
    return lerp(a, b, fy);
  }
  bool empty() const { return levels_.empty(); }

 private:
  // Each level keeps one extra column and row (copies of the last) so the
  // bilinear lookup never reads outside.
  struct Level {
    int nx, ny, stride;
    float cell, inv_cell, max_x, max_y;
    std::vector<Rgbf> v;
  };
  float x0_ = 0, y0_ = 0;
  std::vector<Level> levels_;
};

// A scalar map (e.g. sun visibility), bilinear, clamped.
class ScalarMap {
 public:
  ScalarMap() = default;
  ScalarMap(float x0, float y0, float cell, int nx, int ny, std::vector<float> values)
      : x0_(x0), y0_(y0), inv_cell_(1.0f / cell), nx_(nx), ny_(ny), v_(std::move(values)) {}
  float sample(float x, float y, float outside = 0) const;
  bool empty() const { return v_.empty(); }

 private:
  float x0_ = 0, y0_ = 0, inv_cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<float> v_;
};

struct Material;
// Synthesises the albedo map of a material (deterministic for the seed).
Texture synthesize_texture(const Material& material, uint64_t seed);

}  // namespace ivoa::sim
