#include "depth_sensor.hpp"

#include <algorithm>
#include <cmath>

#include "noise.hpp"

namespace ivoa::sim::detail {
namespace {

// A smooth random field with values spread evenly over [0, 1): blobs of
// dropouts appear where it falls below a pixel's dropout probability.
class BlobField {
 public:
  static const BlobField& instance() {
    static const BlobField field;
    return field;
  }
  float at(int x, int y) const { return v_[static_cast<size_t>((y & (kN - 1)) * kN + (x & (kN - 1)))]; }

 private:
  static constexpr int kN = 256;
  BlobField() : v_(kN * kN) {
    // White noise blurred (three box passes ~ a Gaussian of sigma 3.5 px, on
    // a torus) gives round blobs about 8 px across.
    Rng rng(0xb10bULL);
    std::vector<float> a(kN * kN), b(kN * kN);
    for (float& x : a) x = static_cast<float>(rng.uniform());
    const int r = 3;
    for (int pass = 0; pass < 3; ++pass) {
      for (int y = 0; y < kN; ++y)
        for (int x = 0; x < kN; ++x) {
          float sum = 0;
          for (int k = -r; k <= r; ++k) sum += a[static_cast<size_t>(y * kN + ((x + k) & (kN - 1)))];
          b[static_cast<size_t>(y * kN + x)] = sum;
        }
      for (int y = 0; y < kN; ++y)
        for (int x = 0; x < kN; ++x) {
          float sum = 0;
          for (int k = -r; k <= r; ++k) sum += b[static_cast<size_t>(((y + k) & (kN - 1)) * kN + x)];
          a[static_cast<size_t>(y * kN + x)] = sum;
        }
    }
    std::vector<std::pair<float, int>> order;
    for (int i = 0; i < kN * kN; ++i) order.emplace_back(a[static_cast<size_t>(i)], i);
    // Rank transform: uniform marginal, so a threshold p drops a fraction p.
    std::sort(order.begin(), order.end());
    for (size_t i = 0; i < order.size(); ++i)
      v_[static_cast<size_t>(order[i].second)] = static_cast<float>(i) / static_cast<float>(order.size());
  }
  std::vector<float> v_;
};

// 0 at a, 1 at b (a > b allowed).
float smoothstep(float a, float b, float x) {
  const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

}  // namespace

cv::Mat depth_image(const std::vector<Ranged>& ranged, int width, int height, double focal, double min_range,
                    double max_range, const DepthSensorConfig& c, uint64_t frame) {
  const size_t n = static_cast<size_t>(width) * height;
  thread_local std::vector<float> z, inv_z;  // scratch reused across frames, fully written below
  thread_local std::vector<uint8_t> invalid;
  z.resize(n);
  inv_z.resize(n);
  invalid.resize(n);
  for (size_t i = 0; i < n; ++i) {
    z[i] = ranged[i].depth;
    inv_z[i] = 1.0f / z[i];  // 0 where nothing was hit (z = inf)
  }
  // Depth edges: structured light cannot resolve a pixel that straddles a
  // jump. Invalid where a 4-neighbour differs by more than edge_ratio * z
  // (infinite depths compare as jumps: the comparison is false for them).
  const float ratio = static_cast<float>(c.edge_ratio);
  auto near = [ratio](float a, float b) { return std::abs(a - b) <= ratio * a; };
  for (int y = 0; y < height; ++y) {
    const float* row = z.data() + static_cast<size_t>(y) * width;
    const float* up = y > 0 ? row - width : row;
    const float* down = y + 1 < height ? row + width : row;
    uint8_t* inv = invalid.data() + static_cast<size_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      const float zi = row[x];
      const float left = row[x > 0 ? x - 1 : x], right = row[x + 1 < width ? x + 1 : x];
      inv[x] = !(near(zi, left) && near(zi, right) && near(zi, up[x]) && near(zi, down[x]));
    }
  }
  // Projector shadows: the projector sits to the right of the IR camera, so a
  // point is unlit when something to its right in the image maps at or left
  // of it in the projector (scan right to left keeping the minimum).
  const float fb = static_cast<float>(focal * c.projector_baseline);
  for (int y = 0; y < height; ++y) {
    float min_proj = 1e30f;
    for (int x = width - 1; x >= 0; --x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      if (inv_z[i] == 0) continue;
      const float proj = static_cast<float>(x) - fb * inv_z[i];
      if (proj >= min_proj - 0.5f) invalid[i] = 1;
      else min_proj = std::min(min_proj, proj);
    }
  }
  const NoiseTable& table = NoiseTable::instance();
  const BlobField& blobs = BlobField::instance();
  const uint64_t h = hash_combine(frame, 0xdeb7u);
  const int bx = static_cast<int>(h & 0xff), by = static_cast<int>((h >> 8) & 0xff);
  const float dark = static_cast<float>(c.dark_return), spec_scale = static_cast<float>(c.specular_dropout);
  const float sun_scale = static_cast<float>(c.sunlight_dropout / 16.0);  // reaches the full rate at 4 m
  const float random_dropout = static_cast<float>(c.random_dropout), noise = static_cast<float>(c.noise_coefficient);
  const float* uniforms = table.uniforms();
  const float* normals = table.normals();
  const float lo = static_cast<float>(min_range), hi = static_cast<float>(max_range);
  cv::Mat out(height, width, CV_16UC1);
  for (int y = 0; y < height; ++y) {
    uint16_t* dst = out.ptr<uint16_t>(y);
    const uint32_t offset = NoiseTable::offset(frame, 7, static_cast<uint32_t>(y));
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      dst[x] = 0;
      const float zi = z[i];
      if (invalid[i] || !(zi >= lo && zi <= hi)) continue;
      const Ranged& r = ranged[i];
      // Dropout chance: weak IR return (dark or grazing), mirror-like
      // surfaces, and sunlight washing out the pattern (worse far away).
      const float ret = r.ir_return * 4.0f * std::min(4.0f, inv_z[i] * inv_z[i]);
      const float p_dark = ret >= dark ? 0.0f : smoothstep(dark, dark * 0.3f, ret);
      const float p_spec = std::min(0.9f, spec_scale * r.specular);
      const float p_sun = std::min(0.95f, sun_scale * r.sunlit * zi * zi);
      const float keep = (1 - p_dark) * (1 - p_spec) * (1 - p_sun);
      if (blobs.at(x + bx, y + by) < 1.0f - keep) continue;
      if (uniforms[(offset + static_cast<uint32_t>(x)) & NoiseTable::kMask] < random_dropout) continue;
      const float noisy = zi + noise * zi * zi * normals[(offset + static_cast<uint32_t>(x)) & NoiseTable::kMask];
      const float mm = noisy * 1000.0f + 0.5f;
      dst[x] = static_cast<uint16_t>(mm <= 0 ? 0 : (mm >= 65535.0f ? 65535 : static_cast<int>(mm)));
    }
  }
  return out;
}

}  // namespace ivoa::sim::detail
