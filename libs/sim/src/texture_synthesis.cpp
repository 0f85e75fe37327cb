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
        const float a = lattice[static_cast<size_t>(j) * cx + x0 % cx],
                    b = lattice[static_cast<size_t>(j) * cx + (x0 + 1) % cx];
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

using Srgb = Rgb;  // a painted colour, sRGB

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

// What every painter reads of its material, captured by value in the painters.
struct Look {
  double P;            // texture period, metres
  double c;            // contrast
  double s;            // the material's feature scale, metres
  Rgb a, b;            // colour and secondary colour
  uint64_t cell_seed;  // per-tile / per-brick variation
};

// Noise images for one texture. The order of the calls fixes the random
// draws, and so the texture: painters must keep theirs.
class NoiseMaker {
 public:
  NoiseMaker(const Plan& plan, Rng& rng) : plan_(plan), rng_(rng) {}
  // Lattice cells per period for features of `feature` metres.
  int cells(double feature) const {
    return std::max(1, static_cast<int>(std::lround(plan_.period / std::max(feature, 1e-4))));
  }
  std::shared_ptr<const Fbm> fbm(int c0, int octaves, double persistence, double aspect = 1.0) {
    return std::make_shared<Fbm>(c0, octaves, persistence, rng_, plan_.n, aspect);
  }
  std::shared_ptr<const PeriodicNoise> lattice(int cx, int cy) {
    return std::make_shared<PeriodicNoise>(cx, cy, rng_, plan_.n);
  }
  Rng& rng() { return rng_; }

 private:
  Plan plan_;
  Rng& rng_;
};

// Index of a cell within the period, for cells that repeat every `count`.
int64_t wrapped(int64_t i, int64_t count) { return ((i % count) + count) % count; }

Painter paint_uniform(const Look& k, NoiseMaker& noise) {
  auto low = noise.fbm(2, 2, 0.5);
  return [=](double u, double v) { return scaled(k.a, 1.0 + 0.012 * low->at(u / k.P, v / k.P)); };
}

Painter paint_plaster(const Look& k, NoiseMaker& noise) {
  auto blot = noise.fbm(noise.cells(k.s * 8), 6, 0.6);
  auto grain = noise.lattice(noise.cells(0.003), noise.cells(0.003));
  return [=](double u, double v) {
    const double t = 0.5 + 0.6 * blot->at(u / k.P, v / k.P);
    return scaled(mix(k.a, k.b, t * k.c * 1.6), 1.0 + 0.35 * k.c * grain->at(u / k.P, v / k.P));
  };
}

Painter paint_carpet(const Look& k, NoiseMaker& noise) {
  auto fibre = noise.lattice(noise.cells(k.s * 0.7), noise.cells(k.s * 0.7));
  auto loop = noise.lattice(noise.cells(k.s * 2), noise.cells(k.s * 2));
  auto mottle = noise.fbm(noise.cells(0.15), 3, 0.5);
  return [=](double u, double v) {
    const double f = 0.55 * fibre->at(u / k.P, v / k.P) + 0.45 * loop->at(u / k.P, v / k.P);
    return scaled(mix(k.a, k.b, 0.5 + 0.8 * f * k.c), 1.0 + 0.08 * mottle->at(u / k.P, v / k.P));
  };
}

// Speckle and asphalt: dots over a shaded base; asphalt has more of them.
Painter paint_speckle(const Look& k, NoiseMaker& noise, bool asphalt) {
  auto base = noise.fbm(noise.cells(k.s * 2), 3, 0.6);
  auto dots = noise.lattice(noise.cells(k.s), noise.cells(k.s));
  auto fine = noise.lattice(noise.cells(0.0025), noise.cells(0.0025));
  auto patchy = noise.fbm(noise.cells(0.4), 3, 0.5);
  const double threshold = asphalt ? 0.45 : 0.55;
  return [=](double u, double v) {
    const double d = dots->at(u / k.P, v / k.P);
    const double speck = std::clamp((d - threshold) * 5.0, 0.0, 1.0);
    Srgb col = mix(k.a, k.b, speck * k.c * 1.3);
    const double shade = 1.0 + k.c * (0.25 * base->at(u / k.P, v / k.P) + 0.25 * fine->at(u / k.P, v / k.P)) +
                         0.06 * patchy->at(u / k.P, v / k.P);
    return scaled(col, shade);
  };
}

// Square tiles in grout; a checker alternates the two colours and has light grout.
Painter paint_tiles(const Look& k, NoiseMaker& noise, bool checker) {
  const double s = k.s, grout = std::max(0.004, s * 0.015);
  auto shading = noise.fbm(noise.cells(0.02), 3, 0.5);
  auto fine = noise.lattice(noise.cells(0.003), noise.cells(0.003));
  return [=](double u, double v) {
    const int64_t i = static_cast<int64_t>(std::floor(u / s)), j = static_cast<int64_t>(std::floor(v / s));
    const double fu = u - i * s, fv = v - j * s;
    const double edge = std::min(std::min(fu, s - fu), std::min(fv, s - fv));
    const double in_grout = std::clamp((grout - edge) / 0.0015 + 0.5, 0.0, 1.0);
    const int64_t n_per = static_cast<int64_t>(std::llround(k.P / s));
    const double jitter = cell_random(k.cell_seed, wrapped(i, n_per), wrapped(j, n_per)) - 0.5;
    Srgb tile = checker && ((i + j) & 1) ? k.b : k.a;
    tile = scaled(tile,
                  1.0 + 0.25 * k.c * jitter + 0.06 * shading->at(u / k.P, v / k.P) + 0.04 * fine->at(u / k.P, v / k.P));
    const Srgb grout_colour = scaled(k.b, checker ? 2.5 : 1.0);
    return mix(tile, grout_colour, in_grout * (checker ? 0.5 : 1.0));
  };
}

// Running bond: every other row shifted by half a brick.
Painter paint_bricks(const Look& k, NoiseMaker& noise) {
  const double len = k.s, h = k.s / 3.0, mortar = std::max(0.006, k.s * 0.04);
  auto shading = noise.fbm(noise.cells(0.01), 4, 0.55);
  return [=](double u, double v) {
    const int64_t row = static_cast<int64_t>(std::floor(v / h));
    const double shift = (row & 1) ? len / 2 : 0.0;
    const int64_t col = static_cast<int64_t>(std::floor((u + shift) / len));
    const double fu = u + shift - col * len, fv = v - row * h;
    const double edge = std::min(std::min(fu, len - fu), std::min(fv, h - fv));
    const double in_mortar = std::clamp((mortar / 2 - edge) / 0.002 + 0.5, 0.0, 1.0);
    const int64_t cols = static_cast<int64_t>(std::llround(k.P / len)),
                  rows = static_cast<int64_t>(std::llround(k.P / h));
    const double jitter = cell_random(k.cell_seed, wrapped(col, cols), wrapped(row, rows)) - 0.5;
    const Srgb brick = scaled(k.a, 1.0 + 0.45 * k.c * jitter + 0.25 * k.c * shading->at(u / k.P, v / k.P));
    return mix(brick, k.b, in_mortar);
  };
}

// Planks along u with ring grain and dark seams between them.
Painter paint_wood(const Look& k, NoiseMaker& noise) {
  const double w = k.s;
  auto grain = noise.fbm(noise.cells(0.05), 4, 0.5, 0.15);
  auto fine = noise.lattice(noise.cells(0.004), noise.cells(0.0015));
  return [=](double u, double v) {
    const int64_t plank = static_cast<int64_t>(std::floor(v / w));
    const double fv = v - plank * w;
    const int64_t planks = static_cast<int64_t>(std::llround(k.P / w));
    const double jitter = cell_random(k.cell_seed, 0, wrapped(plank, planks)) - 0.5;
    const double rings = std::sin(kTwoPi * (v / 0.012 + 3.0 * grain->at(u / k.P, v / k.P)));
    const double seam = std::clamp((0.002 - std::min(fv, w - fv)) / 0.001 + 0.5, 0.0, 1.0);
    Srgb col = mix(k.a, k.b, 0.5 + 0.5 * k.c * rings + 0.6 * k.c * jitter);
    col = scaled(col, 1.0 + 0.1 * k.c * fine->at(u / k.P, v / k.P));
    return mix(col, scaled(k.b, 0.5), seam);
  };
}

Painter paint_fabric(const Look& k, NoiseMaker& noise) {
  auto motif = noise.fbm(noise.cells(0.2), 3, 0.5);
  auto fine = noise.lattice(noise.cells(k.s), noise.cells(k.s));
  const int64_t threads = std::max<int64_t>(1, std::llround(k.P / k.s));
  return [=](double u, double v) {
    const double wu = std::sin(kTwoPi * u / k.P * static_cast<double>(threads));
    const double wv = std::sin(kTwoPi * v / k.P * static_cast<double>(threads));
    const double weave = 0.5 * wu * wv;
    const double mo = motif->at(u / k.P, v / k.P);
    Srgb col = mix(k.a, k.b, std::clamp((mo + 0.1) * 4.0, 0.0, 1.0) * k.c);
    return scaled(col, 1.0 + 0.3 * k.c * weave + 0.25 * k.c * fine->at(u / k.P, v / k.P));
  };
}

Painter paint_metal(const Look& k, NoiseMaker& noise) {
  auto brushed = noise.fbm(noise.cells(0.002), 3, 0.5, 0.02);
  auto smudge = noise.fbm(noise.cells(0.2), 2, 0.5);
  return [=](double u, double v) {
    return scaled(mix(k.a, k.b, 0.5 + 0.5 * smudge->at(u / k.P, v / k.P) * k.c * 3),
                  1.0 + 0.6 * k.c * brushed->at(u / k.P, v / k.P));
  };
}

Painter paint_cardboard(const Look& k, NoiseMaker& noise) {
  auto fibres = noise.fbm(noise.cells(k.s), 4, 0.6, 0.3);
  auto blots = noise.fbm(noise.cells(0.1), 3, 0.5);
  return [=](double u, double v) {
    const double t = 0.5 + 0.5 * blots->at(u / k.P, v / k.P);
    return scaled(mix(k.a, k.b, t * k.c), 1.0 + 0.4 * k.c * fibres->at(u / k.P, v / k.P));
  };
}

Painter paint_grass(const Look& k, NoiseMaker& noise) {
  auto blades = noise.fbm(noise.cells(k.s * 0.5), 3, 0.6, 0.25);
  auto clumps = noise.fbm(noise.cells(0.15), 3, 0.5);
  return [=](double u, double v) {
    const double t = 0.5 + 0.7 * blades->at(u / k.P, v / k.P);
    return scaled(mix(k.a, k.b, t), 1.0 + 0.35 * k.c * clumps->at(u / k.P, v / k.P));
  };
}

Painter paint_stripes(const Look& k, NoiseMaker& noise) {
  auto shading = noise.fbm(noise.cells(0.01), 3, 0.5);
  return [=](double u, double v) {
    const double phase = std::fmod(u / (2 * k.s), 1.0);
    const double t = std::clamp((std::abs(phase - 0.5) - 0.25) / 0.01 + 0.5, 0.0, 1.0);
    return scaled(mix(k.a, k.b, t * k.c * 1.5), 1.0 + 0.05 * shading->at(u / k.P, v / k.P));
  };
}

// A grid of framed windows, one bay `s` wide and one storey 2 s high.
Painter paint_facade(const Look& k, NoiseMaker& noise) {
  const double s = k.s, floor_h = 2 * s;
  auto shading = noise.fbm(noise.cells(0.05), 4, 0.55);
  auto glass = noise.fbm(noise.cells(0.5), 3, 0.5);
  return [=](double u, double v) {
    const double fu = std::fmod(u, s) / s, fv = std::fmod(v, floor_h) / floor_h;
    const bool window = fu > 0.2 && fu < 0.8 && fv > 0.3 && fv < 0.8;
    const bool frame = fu > 0.17 && fu < 0.83 && fv > 0.27 && fv < 0.83 && !window;
    if (window) return scaled(mix(k.b, k.a, 0.15 + 0.15 * glass->at(u / k.P, v / k.P)), 1.0);
    if (frame) return Srgb{0.25, 0.25, 0.26};
    return scaled(k.a, 1.0 + 0.2 * k.c * shading->at(u / k.P, v / k.P));
  };
}

Painter paint_ceiling_tiles(const Look& k, NoiseMaker& noise) {
  auto holes = noise.lattice(noise.cells(0.004), noise.cells(0.004));
  return [=](double u, double v) {
    const double fu = std::fmod(u, k.s), fv = std::fmod(v, k.s);
    const double edge = std::min(std::min(fu, k.s - fu), std::min(fv, k.s - fv));
    if (edge < 0.012) return k.b;
    return scaled(k.a, 1.0 - 0.3 * k.c * std::max(0.0f, holes->at(u / k.P, v / k.P) - 0.3f));
  };
}

// Random overlapping rectangles and text-like lines in a few colours.
Painter paint_printed(const Look& k, NoiseMaker& noise) {
  struct Rect {
    double x0, y0, x1, y1;
    Srgb col;
  };
  auto rects = std::make_shared<std::vector<Rect>>();
  const Srgb palette[] = {k.a, k.b, {0.1, 0.1, 0.12}, {0.9, 0.8, 0.2}, {0.2, 0.5, 0.3}};
  Rng& rng = noise.rng();
  for (int i = 0; i < 60; ++i) {
    const double w = rng.uniform(0.02, 0.3) * k.P, h = rng.uniform(0.005, 0.2) * k.P;
    const double x = rng.uniform(0, k.P), y = rng.uniform(0, k.P);
    rects->push_back({x, y, x + w, y + h, palette[rng.uniform_int(0, 4)]});
  }
  auto shading = noise.fbm(noise.cells(0.01), 3, 0.5);
  return [=](double u, double v) {
    Srgb col = k.a;
    for (const Rect& r : *rects) {
      for (int wrap = 0; wrap < 4; ++wrap) {  // rectangles running over the period's edge
        const double uu = u + ((wrap & 1) ? k.P : 0), vv = v + ((wrap & 2) ? k.P : 0);
        if (uu >= r.x0 && uu < r.x1 && vv >= r.y0 && vv < r.y1) col = r.col;
      }
    }
    const Srgb out = {k.a[0] + (col[0] - k.a[0]) * k.c, k.a[1] + (col[1] - k.a[1]) * k.c,
                      k.a[2] + (col[2] - k.a[2]) * k.c};
    return scaled(out, 1.0 + 0.04 * shading->at(u / k.P, v / k.P));
  };
}

Painter make_painter(const Material& m, const Plan& plan, Rng& rng) {
  const uint64_t cell_seed = rng.next();
  const Look k{plan.period, m.contrast, m.scale, m.color, m.color2, cell_seed};
  NoiseMaker noise(plan, rng);
  switch (m.pattern) {
    case Pattern::kUniform: return paint_uniform(k, noise);
    case Pattern::kPlaster: return paint_plaster(k, noise);
    case Pattern::kCarpet: return paint_carpet(k, noise);
    case Pattern::kSpeckle: return paint_speckle(k, noise, false);
    case Pattern::kAsphalt: return paint_speckle(k, noise, true);
    case Pattern::kTiles: return paint_tiles(k, noise, false);
    case Pattern::kChecker: return paint_tiles(k, noise, true);
    case Pattern::kBricks: return paint_bricks(k, noise);
    case Pattern::kWood: return paint_wood(k, noise);
    case Pattern::kFabric: return paint_fabric(k, noise);
    case Pattern::kMetal: return paint_metal(k, noise);
    case Pattern::kCardboard: return paint_cardboard(k, noise);
    case Pattern::kGrass: return paint_grass(k, noise);
    case Pattern::kStripes: return paint_stripes(k, noise);
    case Pattern::kFacade: return paint_facade(k, noise);
    case Pattern::kCeilingTiles: return paint_ceiling_tiles(k, noise);
    case Pattern::kPrinted: return paint_printed(k, noise);
  }
  return [k](double, double) { return k.a; };
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
      pixels[static_cast<size_t>(j) * plan.n + i] =
          Rgbf(to_linear_fast(s[0]), to_linear_fast(s[1]), to_linear_fast(s[2]));
    }
  return Texture(plan.n, texel, pixels);
}

}  // namespace ivoa::sim
