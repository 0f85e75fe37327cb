// Procedural, tileable albedo maps for the material patterns. Every map is
// periodic (the noise lattices wrap), so surfaces of any size can be covered.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>

#include "rng.hpp"
#include "texture.hpp"

namespace ivoa::sim {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// Value noise on a wrapping lattice, values in [-1, 1], smooth (smoothstep)
// in between, evaluated once at the n x n texel centres of a texture
// (separably: along x for each lattice row, then along y).
class PeriodicNoise {
 public:
  PeriodicNoise(int cells_x, int cells_y, Rng& rng, int n) : n_(n), image_(static_cast<size_t>(n) * n) {
    const int cx = std::max(1, cells_x), cy = std::max(1, cells_y);
    std::vector<float> lattice(static_cast<size_t>(cx) * cy);
    for (float& x : lattice) x = static_cast<float>(rng.uniform(-1.0, 1.0));
    std::vector<float> rows(static_cast<size_t>(cy) * n);
    for (int j = 0; j < cy; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = (i + 0.5) * cx / n;
        const int x0 = static_cast<int>(x);
        const double t = x - x0, s = t * t * (3 - 2 * t);
        const float a = lattice[static_cast<size_t>(j) * cx + x0 % cx], b = lattice[static_cast<size_t>(j) * cx + (x0 + 1) % cx];
        rows[static_cast<size_t>(j) * n + i] = static_cast<float>(a + (b - a) * s);
      }
    for (int k = 0; k < n; ++k) {
      const double y = (k + 0.5) * cy / n;
      const int y0 = static_cast<int>(y);
      const float s = static_cast<float>((y - y0) * (y - y0) * (3 - 2 * (y - y0)));
      const float* ra = rows.data() + static_cast<size_t>(y0 % cy) * n;
      const float* rb = rows.data() + static_cast<size_t>((y0 + 1) % cy) * n;
      float* out = image_.data() + static_cast<size_t>(k) * n;
      for (int i = 0; i < n; ++i) out[i] = ra[i] + (rb[i] - ra[i]) * s;
    }
  }
  // (fx, fy) in [0, 1) of the texture period, at a texel centre.
  float at(double fx, double fy) const {
    const int i = static_cast<int>(fx * n_) & (n_ - 1), j = static_cast<int>(fy * n_) & (n_ - 1);
    return image_[static_cast<size_t>(j) * n_ + i];
  }
  const std::vector<float>& image() const { return image_; }

 private:
  int n_;
  std::vector<float> image_;
};

// Sum of octaves: the first has `cells` lattice cells per period, each next doubles.
class Fbm {
 public:
  Fbm(int cells, int octaves, double persistence, Rng& rng, int n, double aspect = 1.0)
      : n_(n), image_(static_cast<size_t>(n) * n, 0.0f) {
    double amp = 1, norm = 0;
    for (int o = 0; o < octaves; ++o) {
      const int c = cells << o;
      const PeriodicNoise octave(std::max(1, static_cast<int>(c * aspect)), c, rng, n);
      const std::vector<float>& img = octave.image();
      for (size_t k = 0; k < image_.size(); ++k) image_[k] += static_cast<float>(amp) * img[k];
      norm += amp;
      amp *= persistence;
    }
    for (float& v : image_) v = static_cast<float>(v / norm * 1.6);  // roughly [-1, 1]
  }
  float at(double fx, double fy) const {
    const int i = static_cast<int>(fx * n_) & (n_ - 1), j = static_cast<int>(fy * n_) & (n_ - 1);
    return image_[static_cast<size_t>(j) * n_ + i];
  }

 private:
  int n_;
  std::vector<float> image_;
};

using Srgb = std::array<double, 3>;

Srgb mix(const Rgb& a, const Rgb& b, double t) {
  t = std::clamp(t, 0.0, 1.0);
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
}
Srgb scaled(const Srgb& c, double s) { return {c[0] * s, c[1] * s, c[2] * s}; }

// Periodic cell hash for per-tile / per-brick variation.
double cell_random(uint64_t seed, int64_t i, int64_t j) {
  return static_cast<double>(mix64(hash_combine(seed, static_cast<uint64_t>(i * 73856093LL ^ j * 19349663LL))) >> 11) *
         (1.0 / 9007199254740992.0);
}

struct Plan {
  int n;          // texels per side (power of two)
  double period;  // metres per side
};

// Period and resolution: fine textures get ~1.5 mm texels (the nearest floor
// the cameras see is ~0.4 m away, where a pixel covers ~1 mm); periodic
// patterns hold an integer number of periods.
Plan plan_for(const Material& m) {
  auto periodic = [](double p, double min_period) {
    const int k = std::max(1, static_cast<int>(std::ceil(min_period / p)));
    const double period = k * p;
    int n = 1024;
    while (n > 256 && period / (n / 2) < 0.0016) n /= 2;
    return Plan{n, period};
  };
  switch (m.pattern) {
    case Pattern::kUniform: return {64, 4.0};
    case Pattern::kTiles:
    case Pattern::kChecker: return periodic(2 * m.scale, 1.2);
    case Pattern::kBricks: return periodic(m.scale, 1.2);
    case Pattern::kStripes: return periodic(2 * m.scale, 1.0);
    case Pattern::kWood: return periodic(m.scale, 1.2);
    case Pattern::kFacade: return periodic(m.scale, 5.0);
    case Pattern::kCeilingTiles: return periodic(m.scale, 2.4);
    case Pattern::kPlaster: return m.scale >= 0.1 ? Plan{512, 3.0} : Plan{1024, 1.5};
    case Pattern::kPrinted: return {512, std::max(0.5, m.scale * 8)};
    default: return {1024, 1.5};
  }
}

using Painter = std::function<Srgb(double u, double v)>;  // metres within one period

Painter make_painter(const Material& m, const Plan& plan, Rng& rng) {
  const double P = plan.period, c = m.contrast;
  const Rgb a = m.color, b = m.color2;
  const uint64_t cell_seed = rng.next();
  auto cells = [&](double feature) { return std::max(1, static_cast<int>(std::lround(P / std::max(feature, 1e-4)))); };
  auto fbm = [&](int c0, int octaves, double persistence, double aspect = 1.0) {
    return std::make_shared<Fbm>(c0, octaves, persistence, rng, plan.n, aspect);
  };
  auto lattice = [&](int cx, int cy) { return std::make_shared<PeriodicNoise>(cx, cy, rng, plan.n); };

  switch (m.pattern) {
    case Pattern::kUniform: {
      auto low = fbm(2, 2, 0.5);
      return [=](double u, double v) { return scaled(mix(a, a, 0), 1.0 + 0.012 * low->at(u / P, v / P)); };
    }
    case Pattern::kPlaster: {
      auto blot = fbm(cells(m.scale * 8), 6, 0.6);
      auto grain = lattice(cells(0.003), cells(0.003));
      return [=](double u, double v) {
        const double t = 0.5 + 0.6 * blot->at(u / P, v / P);
        return scaled(mix(a, b, t * c * 1.6), 1.0 + 0.35 * c * grain->at(u / P, v / P));
      };
    }
    case Pattern::kCarpet: {
      auto fibre = lattice(cells(m.scale * 0.7), cells(m.scale * 0.7));
      auto loop = lattice(cells(m.scale * 2), cells(m.scale * 2));
      auto mottle = fbm(cells(0.15), 3, 0.5);
      return [=](double u, double v) {
        const double f = 0.55 * fibre->at(u / P, v / P) + 0.45 * loop->at(u / P, v / P);
        return scaled(mix(a, b, 0.5 + 0.8 * f * c), 1.0 + 0.08 * mottle->at(u / P, v / P));
      };
    }
    case Pattern::kSpeckle:
    case Pattern::kAsphalt: {
      const bool asphalt = m.pattern == Pattern::kAsphalt;
      auto base = fbm(cells(m.scale * 2), 3, 0.6);
      auto dots = lattice(cells(m.scale), cells(m.scale));
      auto fine = lattice(cells(0.0025), cells(0.0025));
      auto patchy = fbm(cells(0.4), 3, 0.5);
      const double threshold = asphalt ? 0.45 : 0.55;
      return [=](double u, double v) {
        const double d = dots->at(u / P, v / P);
        const double speck = std::clamp((d - threshold) * 5.0, 0.0, 1.0);
        Srgb col = mix(a, b, speck * c * 1.3);
        const double shade = 1.0 + c * (0.25 * base->at(u / P, v / P) + 0.25 * fine->at(u / P, v / P)) +
                             0.06 * patchy->at(u / P, v / P);
        return scaled(col, shade);
      };
    }
    case Pattern::kTiles:
    case Pattern::kChecker: {
      const bool checker = m.pattern == Pattern::kChecker;
      const double s = m.scale, grout = std::max(0.004, s * 0.015);
      auto noise = fbm(cells(0.02), 3, 0.5);
      auto fine = lattice(cells(0.003), cells(0.003));
      return [=](double u, double v) {
        const int64_t i = static_cast<int64_t>(std::floor(u / s)), j = static_cast<int64_t>(std::floor(v / s));
        const double fu = u - i * s, fv = v - j * s;
        const double edge = std::min(std::min(fu, s - fu), std::min(fv, s - fv));
        const double in_grout = std::clamp((grout - edge) / 0.0015 + 0.5, 0.0, 1.0);
        const int64_t n_per = static_cast<int64_t>(std::llround(P / s));
        const double jitter = cell_random(cell_seed, ((i % n_per) + n_per) % n_per, ((j % n_per) + n_per) % n_per) - 0.5;
        Srgb tile = checker && ((i + j) & 1) ? Srgb{b[0], b[1], b[2]} : Srgb{a[0], a[1], a[2]};
        tile = scaled(tile, 1.0 + 0.25 * c * jitter + 0.06 * noise->at(u / P, v / P) + 0.04 * fine->at(u / P, v / P));
        const Srgb g = scaled(Srgb{b[0], b[1], b[2]}, checker ? 2.5 : 1.0);
        return mix({tile[0], tile[1], tile[2]}, {g[0], g[1], g[2]}, in_grout * (checker ? 0.5 : 1.0));
      };
    }
    case Pattern::kBricks: {
      const double len = m.scale, h = m.scale / 3.0, mortar = std::max(0.006, m.scale * 0.04);
      auto noise = fbm(cells(0.01), 4, 0.55);
      return [=](double u, double v) {
        const int64_t row = static_cast<int64_t>(std::floor(v / h));
        const double shift = (row & 1) ? len / 2 : 0.0;
        const int64_t col = static_cast<int64_t>(std::floor((u + shift) / len));
        const double fu = u + shift - col * len, fv = v - row * h;
        const double edge = std::min(std::min(fu, len - fu), std::min(fv, h - fv));
        const double in_mortar = std::clamp((mortar / 2 - edge) / 0.002 + 0.5, 0.0, 1.0);
        const int64_t cols = static_cast<int64_t>(std::llround(P / len)), rows = static_cast<int64_t>(std::llround(P / h));
        const double jitter = cell_random(cell_seed, ((col % cols) + cols) % cols, ((row % rows) + rows) % rows) - 0.5;
        const Srgb brick = scaled(Srgb{a[0], a[1], a[2]}, 1.0 + 0.45 * c * jitter + 0.25 * c * noise->at(u / P, v / P));
        return mix({brick[0], brick[1], brick[2]}, b, in_mortar);
      };
    }
    case Pattern::kWood: {
      const double w = m.scale;
      auto grain = fbm(cells(0.05), 4, 0.5, 0.15);
      auto fine = lattice(cells(0.004), cells(0.0015));
      return [=](double u, double v) {
        const int64_t plank = static_cast<int64_t>(std::floor(v / w));
        const double fv = v - plank * w;
        const int64_t planks = static_cast<int64_t>(std::llround(P / w));
        const double jitter = cell_random(cell_seed, 0, ((plank % planks) + planks) % planks) - 0.5;
        const double rings = std::sin(kTwoPi * (v / 0.012 + 3.0 * grain->at(u / P, v / P)));
        const double seam = std::clamp((0.002 - std::min(fv, w - fv)) / 0.001 + 0.5, 0.0, 1.0);
        Srgb col = mix(a, b, 0.5 + 0.5 * c * rings + 0.6 * c * jitter);
        col = scaled(col, 1.0 + 0.1 * c * fine->at(u / P, v / P));
        return mix({col[0], col[1], col[2]}, {b[0] * 0.5, b[1] * 0.5, b[2] * 0.5}, seam);
      };
    }
    case Pattern::kFabric: {
      const double s = m.scale;
      auto motif = fbm(cells(0.2), 3, 0.5);
      auto fine = lattice(cells(s), cells(s));
      const int64_t threads = std::max<int64_t>(1, std::llround(P / s));
      return [=](double u, double v) {
        const double wu = std::sin(kTwoPi * u / P * static_cast<double>(threads));
        const double wv = std::sin(kTwoPi * v / P * static_cast<double>(threads));
        const double weave = 0.5 * wu * wv;
        const double mo = motif->at(u / P, v / P);
        Srgb col = mix(a, b, std::clamp((mo + 0.1) * 4.0, 0.0, 1.0) * c);
        return scaled(col, 1.0 + 0.3 * c * weave + 0.25 * c * fine->at(u / P, v / P));
      };
    }
    case Pattern::kMetal: {
      auto brushed = fbm(cells(0.002), 3, 0.5, 0.02);
      auto smudge = fbm(cells(0.2), 2, 0.5);
      return [=](double u, double v) {
        return scaled(mix(a, b, 0.5 + 0.5 * smudge->at(u / P, v / P) * c * 3),
                      1.0 + 0.6 * c * brushed->at(u / P, v / P));
      };
    }
    case Pattern::kCardboard: {
      auto fibres = fbm(cells(m.scale), 4, 0.6, 0.3);
      auto blots = fbm(cells(0.1), 3, 0.5);
      return [=](double u, double v) {
        const double t = 0.5 + 0.5 * blots->at(u / P, v / P);
        return scaled(mix(a, b, t * c), 1.0 + 0.4 * c * fibres->at(u / P, v / P));
      };
    }
    case Pattern::kGrass: {
      auto blades = fbm(cells(m.scale * 0.5), 3, 0.6, 0.25);
      auto clumps = fbm(cells(0.15), 3, 0.5);
      return [=](double u, double v) {
        const double t = 0.5 + 0.7 * blades->at(u / P, v / P);
        return scaled(mix(a, b, t), 1.0 + 0.35 * c * clumps->at(u / P, v / P));
      };
    }
    case Pattern::kStripes: {
      const double s = m.scale;
      auto noise = fbm(cells(0.01), 3, 0.5);
      return [=](double u, double v) {
        const double phase = std::fmod(u / (2 * s), 1.0);
        const double t = std::clamp((std::abs(phase - 0.5) - 0.25) / 0.01 + 0.5, 0.0, 1.0);
        return scaled(mix(a, b, t * c * 1.5), 1.0 + 0.05 * noise->at(u / P, v / P));
      };
    }
    case Pattern::kFacade: {
      const double s = m.scale, floor_h = 2 * s;  // window bay width and storey height
      auto noise = fbm(cells(0.05), 4, 0.55);
      auto glass = fbm(cells(0.5), 3, 0.5);
      return [=](double u, double v) {
        const double fu = std::fmod(u, s) / s, fv = std::fmod(v, floor_h) / floor_h;
        const bool window = fu > 0.2 && fu < 0.8 && fv > 0.3 && fv < 0.8;
        const bool frame = fu > 0.17 && fu < 0.83 && fv > 0.27 && fv < 0.83 && !window;
        if (window) return scaled(mix(b, a, 0.15 + 0.15 * glass->at(u / P, v / P)), 1.0);
        if (frame) return Srgb{0.25, 0.25, 0.26};
        return scaled(Srgb{a[0], a[1], a[2]}, 1.0 + 0.2 * c * noise->at(u / P, v / P));
      };
    }
    case Pattern::kCeilingTiles: {
      const double s = m.scale;
      auto holes = lattice(cells(0.004), cells(0.004));
      return [=](double u, double v) {
        const double fu = std::fmod(u, s), fv = std::fmod(v, s);
        const double edge = std::min(std::min(fu, s - fu), std::min(fv, s - fv));
        if (edge < 0.012) return Srgb{b[0], b[1], b[2]};
        return scaled(Srgb{a[0], a[1], a[2]}, 1.0 - 0.3 * c * std::max(0.0f, holes->at(u / P, v / P) - 0.3f));
      };
    }
    case Pattern::kPrinted: {
      // Random overlapping rectangles and text-like lines in a few colours.
      struct Rect {
        double x0, y0, x1, y1;
        Srgb col;
      };
      auto rects = std::make_shared<std::vector<Rect>>();
      const Srgb palette[] = {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}, {0.1, 0.1, 0.12}, {0.9, 0.8, 0.2}, {0.2, 0.5, 0.3}};
      for (int i = 0; i < 60; ++i) {
        const double w = rng.uniform(0.02, 0.3) * P, h = rng.uniform(0.005, 0.2) * P;
        const double x = rng.uniform(0, P), y = rng.uniform(0, P);
        rects->push_back({x, y, x + w, y + h, palette[rng.uniform_int(0, 4)]});
      }
      auto noise = fbm(cells(0.01), 3, 0.5);
      return [=](double u, double v) {
        Srgb col{a[0], a[1], a[2]};
        for (const Rect& r : *rects) {
          for (int wrap = 0; wrap < 4; ++wrap) {
            const double uu = u + ((wrap & 1) ? P : 0), vv = v + ((wrap & 2) ? P : 0);
            if (uu >= r.x0 && uu < r.x1 && vv >= r.y0 && vv < r.y1) col = r.col;
          }
        }
        const Srgb base{a[0], a[1], a[2]};
        Srgb out = {base[0] + (col[0] - base[0]) * c, base[1] + (col[1] - base[1]) * c, base[2] + (col[2] - base[2]) * c};
        return scaled(out, 1.0 + 0.04 * noise->at(u / P, v / P));
      };
    }
  }
  return [=](double, double) { return Srgb{a[0], a[1], a[2]}; };
}

// sRGB -> linear through a table: pow() per texel would dominate synthesis.
float to_linear_fast(double c) {
  static const std::vector<float> lut = [] {
    std::vector<float> t(4097);
    for (int i = 0; i <= 4096; ++i) t[static_cast<size_t>(i)] = srgb_to_linear(i / 4096.0);
    return t;
  }();
  const int i = static_cast<int>(std::clamp(c, 0.0, 1.0) * 4096.0 + 0.5);
  return lut[static_cast<size_t>(i)];
}

}  // namespace

Texture synthesize_texture(const Material& m, uint64_t seed) {
  const Plan plan = plan_for(m);
  Rng rng(seed);
  const Painter paint = make_painter(m, plan, rng);
  const double texel = plan.period / plan.n;
  std::vector<Rgbf> pixels(static_cast<size_t>(plan.n) * plan.n);
  for (int j = 0; j < plan.n; ++j)
    for (int i = 0; i < plan.n; ++i) {
      const Srgb s = paint((i + 0.5) * texel, (j + 0.5) * texel);
      pixels[static_cast<size_t>(j) * plan.n + i] = Rgbf(to_linear_fast(s[0]), to_linear_fast(s[1]), to_linear_fast(s[2]));
    }
  return Texture(plan.n, texel, pixels);
}

}  // namespace ivoa::sim
