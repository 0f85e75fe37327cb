#include "texture.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>

namespace ivoa::sim {
namespace {

uint32_t encode_texel(const Rgbf& c) {
  auto ch = [](float v) {
    const float e = std::sqrt(std::max(0.0f, std::min(1.0f, v))) * 255.0f + 0.5f;
    return static_cast<uint32_t>(e);
  };
  return ch(c.r) | (ch(c.g) << 8) | (ch(c.b) << 16);
}

}  // namespace

HugeBuffer::HugeBuffer(size_t n) : size_(n) {
  constexpr size_t kHuge = 2u << 20;
  const size_t bytes = (n * sizeof(uint32_t) + kHuge - 1) / kHuge * kHuge;
  data_ = static_cast<uint32_t*>(std::aligned_alloc(kHuge, bytes));
  if (!data_) throw std::bad_alloc();
  madvise(data_, bytes, MADV_HUGEPAGE);  // a hint; fine if refused
}

HugeBuffer::~HugeBuffer() { std::free(data_); }

Texture::Texture(int size, double texel_m, const std::vector<Rgbf>& linear)
    : size_(size), inv_texel_(static_cast<float>(1.0 / texel_m)) {
  std::vector<Rgbf> level = linear;
  int n = size;
  double sum_r = 0, sum_g = 0, sum_b = 0;
  for (const Rgbf& c : linear) {
    sum_r += c.r;
    sum_g += c.g;
    sum_b += c.b;
  }
  const double count = static_cast<double>(linear.size());
  mean_ = Rgbf(static_cast<float>(sum_r / count), static_cast<float>(sum_g / count), static_cast<float>(sum_b / count));
  size_t total = 0;
  for (int m = size; m >= 1; m /= 2) total += static_cast<size_t>(m + 1) * (m + 1);
  data_ = HugeBuffer(total);
  lod_scale_ = inv_texel_ * 1.25f;
  size_t base = 0;
  // Down to 1 x 1: rough reflections of far surfaces need the coarsest averages.
  while (n >= 1 && levels_ < 16) {
    Level& lv = level_[levels_];
    lv.texels = data_.data() + base;
    lv.scale = inv_texel_ / static_cast<float>(1 << levels_);
    lv.mask = n - 1;
    lv.stride = n + 1;
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x)
        data_[base + static_cast<size_t>(y) * (n + 1) + x] =
            encode_texel(level[static_cast<size_t>(y % n) * n + (x % n)]);
    base += static_cast<size_t>(n + 1) * (n + 1);
    ++levels_;
    if (n == 1) break;
    const int m = n / 2;
    std::vector<Rgbf> next(static_cast<size_t>(m) * m);
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        const size_t a = static_cast<size_t>(2 * y) * n + 2 * x;
        next[static_cast<size_t>(y) * m + x] = (level[a] + level[a + 1] + level[a + n] + level[a + n + 1]) * 0.25f;
      }
    level.swap(next);
    n = m;
  }
}

namespace {

// Pads a level with a copy of its last column and row.
std::vector<Rgbf> padded(const std::vector<Rgbf>& v, int nx, int ny) {
  std::vector<Rgbf> out(static_cast<size_t>(nx + 1) * (ny + 1));
  for (int y = 0; y <= ny; ++y)
    for (int x = 0; x <= nx; ++x)
      out[static_cast<size_t>(y) * (nx + 1) + x] =
          v[static_cast<size_t>(std::min(y, ny - 1)) * nx + std::min(x, nx - 1)];
  return out;
}

}  // namespace

RadianceMap::RadianceMap(float x0, float y0, float cell, int nx, int ny, std::vector<Rgbf> values, int levels)
    : x0_(x0), y0_(y0) {
  std::vector<Rgbf> current = std::move(values);
  for (int l = 0; l < levels; ++l) {
    Level lv;
    lv.nx = nx;
    lv.ny = ny;
    lv.stride = nx + 1;
    lv.cell = cell;
    lv.inv_cell = 1.0f / cell;
    lv.max_x = static_cast<float>(nx - 1) - 1e-3f;
    lv.max_y = static_cast<float>(ny - 1) - 1e-3f;
    lv.v = padded(current, nx, ny);
    levels_.push_back(std::move(lv));
    if (nx < 2 || ny < 2) break;
    const int mx = (nx + 1) / 2, my = (ny + 1) / 2;
    std::vector<Rgbf> next(static_cast<size_t>(mx) * my);
    for (int y = 0; y < my; ++y)
      for (int x = 0; x < mx; ++x) {
        Rgbf s(0.0f);
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
            s += current[static_cast<size_t>(std::min(ny - 1, 2 * y + dy)) * nx + std::min(nx - 1, 2 * x + dx)];
        next[static_cast<size_t>(y) * mx + x] = s * 0.25f;
      }
    current.swap(next);
    nx = mx;
    ny = my;
    cell *= 2;
  }
}

float ScalarMap::sample(float x, float y, float outside) const {
  if (v_.empty()) return outside;
  const float gx = (x - x0_) * inv_cell_ - 0.5f, gy = (y - y0_) * inv_cell_ - 0.5f;
  if (gx < -1 || gy < -1 || gx > static_cast<float>(nx_) || gy > static_cast<float>(ny_)) return outside;
  const float cx = std::max(0.0f, std::min(static_cast<float>(nx_ - 1) - 1e-3f, gx));
  const float cy = std::max(0.0f, std::min(static_cast<float>(ny_ - 1) - 1e-3f, gy));
  const int ix = static_cast<int>(cx), iy = static_cast<int>(cy);
  const float fx = cx - static_cast<float>(ix), fy = cy - static_cast<float>(iy);
  const int ix1 = std::min(ix + 1, nx_ - 1), iy1 = std::min(iy + 1, ny_ - 1);
  auto at = [&](int xx, int yy) { return v_[static_cast<size_t>(yy) * nx_ + xx]; };
  return (at(ix, iy) * (1 - fx) + at(ix1, iy) * fx) * (1 - fy) + (at(ix, iy1) * (1 - fx) + at(ix1, iy1) * fx) * fy;
}

}  // namespace ivoa::sim
