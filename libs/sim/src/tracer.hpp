#pragma once
// Ray casting one camera for one frame. Acceleration: every solid's angular
// extent as seen from the camera is binned by azimuth once per frame, sorted
// by distance; a pixel tests only the solids of its azimuth bin, nearest
// first, and stops as soon as the next one starts beyond its current hit.
// The ground is intersected analytically (precomputed per pixel), and a
// mirror-like floor continues the same 2-D ray with z mirrored, so the
// reflection reuses the bin's list.
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "camera_rays.hpp"
#include "color.hpp"
#include "geometry.hpp"
#include "ivoa/sim/pose.hpp"
#include "scene_data.hpp"

namespace ivoa::sim::detail {

// What a camera pixel sees.
struct Shaded {
  Rgbf radiance;
  float depth = 0;        // planar depth of the first surface (inf: sky)
  float specular = 0;     // luminance of the mirror / highlight part of the radiance
  uint8_t surface = 0;    // SURFACE_*
  uint8_t phenomena = 0;  // PHENOMENON_* known from the geometry and materials
  uint16_t padding = 0;   // keeps the struct 24 bytes: copies without overlapping stores
};

// What a depth-sensor pixel sees.
struct Ranged {
  float depth = 0;      // planar depth (inf: nothing)
  float ir_return = 0;  // IR albedo x cosine of incidence
  float specular = 0;   // mirror reflectance (and smoothness) of the surface
  float sunlit = 0;     // direct sun on the surface, 0..1 scaled by irradiance
};

class Tracer {
 public:
  Tracer(const SceneData& scene, const CameraRays& rays, const Pose2D& pose, bool accelerate);

  // Shades the whole image (width x height into out, row-major). Glossy
  // reflections are traced on a sparse lattice (every 2nd or 4th pixel by
  // roughness) and interpolated between: the surface blurs them over more
  // pixels anyway. Mirror-like ones (water) are traced at every pixel.
  // rows_done(y0, y1) is called as soon as rows [y0, y1) of out are final,
  // while they are still in cache.
  void shade_image(Shaded* out, const std::function<void(int, int)>& rows_done) const;
  Ranged range(int pixel) const;

 private:
  struct Candidate {
    float s_min;  // horizontal distance from the camera to the footprint
    uint32_t prism;
    uint8_t circle;
    float lox, loy;  // camera origin in the footprint's frame (circle: origin - centre, world)
    float c, s;      // robot-frame direction -> footprint frame
    float hx, hy, z0, z1;
  };
  struct Hit {
    float s = kInf;  // horizontal distance along the ray
    int candidate = -1;
    int face = kFaceRound;  // a Face; int-sized so the struct is copied without partial stores
  };
  struct Ray {     // one pixel's ray in this frame
    float ux, uy;  // robot frame horizontal direction
    float wx, wy;  // world frame
    float slope, inv_slope, len, inv_len;
    int bin;
  };

  void build_candidates(bool accelerate);
  Candidate make_candidate(uint32_t prism) const;
  // Azimuths [lo, hi] (world frame, radians) a solid covers as seen from the camera.
  std::pair<float, float> azimuth_extent(const Prism& p, float s_min) const;
  // Sorts the candidates into their azimuth bins (spans[k] holds all[span_owner[k]]).
  void fill_bins(const std::vector<Candidate>& all, const std::vector<std::pair<int, int>>& spans,
                 const std::vector<size_t>& span_owner);
  inline Ray make_ray(const PixelRay& r) const;
  // The nearest solid a primary ray meets before it reaches the floor
  // (falling) or the ceiling (rising); `s_reach` is set to that limit.
  inline Hit first_solid(const PixelRay& pr, const Ray& ray, float& s_reach) const;
  // Where a falling primary ray meets the floor, world frame.
  void floor_point(const PixelRay& pr, float& x, float& y) const {
    x = px_ + cos_yaw_ * pr.floor_x - sin_yaw_ * pr.floor_y;
    y = py_ + sin_yaw_ * pr.floor_x + cos_yaw_ * pr.floor_y;
  }
  // False when no solid of the ray's azimuth bin starts before s_hi (nearest() would find none).
  bool bin_may_hit(const Ray& ray, float s_hi) const;
  // Nearest solid along the ray with s in [s_lo, s_hi); mirrored: below the floor.
  void nearest(const Ray& ray, float s_lo, float s_hi, bool mirrored, Hit& best) const;
  void shade_solid(const Ray& ray, const Hit& hit, bool mirrored, float extra_blur, Shaded& out) const;
  // An ordinary floor pixel, located by shade_primary and shaded by
  // finish_floor: done in a second tight loop, where consecutive texture
  // lookups overlap in the processor instead of waiting on each other.
  struct FloorSample {
    int pixel;
    float x, y;  // world
    uint16_t material;
  };
  // What the pixel sees. Returns true for an ordinary floor pixel, which it
  // leaves in *floor for finish_floor.
  bool shade_primary(int pixel, Shaded& out, float& fresnel, FloorSample* floor) const;
  // The floor's own (diffuse) radiance; `fresnel` > 0 when a reflection must be added.
  void finish_floor(const FloorSample& f, Shaded& out, float& fresnel, float& roughness) const;
  // shade_image's passes over rows [y0, y1): what each pixel sees and its
  // reflection lattice spacing; the reflections traced on the lattice; the
  // interpolated ones and the blend into the radiance.
  static constexpr int kBandRows = 8;  // a multiple of the widest lattice spacing (4)
  void shade_band(int y0, int y1, Shaded* out, float* fresnel, float* roughness, uint8_t* step,
                  FloorSample* floor) const;
  bool interpolated(const uint8_t* step, int x, int y) const;
  void trace_reflections(int y0, int y1, uint8_t* step, const float* roughness, Rgbf* reflected) const;
  void blend_reflections(int y0, int y1, const uint8_t* step, const float* fresnel, const Rgbf* reflected,
                         Shaded* out) const;
  // Mirror image plus highlight lobes seen in the floor at a pixel.
  Rgbf floor_reflection(int pixel, float roughness) const;
  static void add_reflection(Shaded& out, float fresnel, const Rgbf& reflected);
  void shade_pit(const Ray& ray, const FloorFeature& pit, float s_floor, Shaded& out) const;
  Rgbf reflection(const Ray& ray, float s_floor, float roughness) const;
  Rgbf sky(float dx, float dy, float dz, float blur) const;
  Rgbf light_lobes(const Ray& ray, float x, float y, float roughness) const;
  const FloorFeature* floor_feature(float x, float y, uint16_t& material) const;

  const SceneData& scene_;
  const CameraRays& rays_;
  float ox_, oy_, oz_;  // camera origin, world
  float px_, py_;       // robot position, world
  float cos_yaw_, sin_yaw_;
  Pose2D pose_;
  float s_ceiling_up_ = kInf;  // (ceiling - oz): divide by slope
  std::vector<Candidate> candidates_;
  std::vector<uint32_t> bin_start_;  // candidates of bin b: [bin_start_[b], bin_start_[b + 1])
  bool brute_force_ = false;
  std::vector<uint32_t> glare_lights_;  // lights that make highlight lobes on glossy floors
};

}  // namespace ivoa::sim::detail
