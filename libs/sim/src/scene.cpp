#include "ivoa/sim/scene.hpp"

#include <algorithm>
#include <cmath>

#include "geometry.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "scene_builder.hpp"

namespace ivoa::sim {

const char* to_string(TruthState state) {
  switch (state) {
    case TruthState::kFree: return "free";
    case TruthState::kObstacle: return "obstacle";
    case TruthState::kHole: return "hole";
  }
  return "?";
}

namespace detail {

double feature_distance(const FloorFeature& f, double x, double y) {
  float lxf, lyf;
  to_local(f, static_cast<float>(x), static_cast<float>(y), lxf, lyf);
  const double lx = std::abs(lxf), ly = std::abs(lyf), a = f.hx, b = f.hy;
  if (!f.ellipse) {
    const double dx = lx - a, dy = ly - b;
    const double outside = std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
    return outside > 0 ? outside : std::max(dx, dy);
  }
  // Closest point on the ellipse (a cos t, b sin t) by Newton's method on t.
  double t = std::atan2(a * ly, b * lx);
  for (int i = 0; i < 12; ++i) {
    const double c = std::cos(t), s = std::sin(t);
    const double ex = a * c - lx, ey = b * s - ly;
    const double g = -a * s * ex + b * c * ey;  // derivative of squared distance / 2
    const double h = a * a * s * s + b * b * c * c - a * c * ex - b * s * ey;
    if (std::abs(h) < 1e-12) break;
    t = std::clamp(t - g / h, 0.0, M_PI / 2);
  }
  const double d = std::hypot(a * std::cos(t) - lx, b * std::sin(t) - ly);
  const double q = (lx / a) * (lx / a) + (ly / b) * (ly / b);
  return q <= 1.0 ? -d : d;
}

void build_plan_grid(SceneData& s) {
  PlanGrid& g = s.grid;
  Eigen::AlignedBox2d box = s.bounds;
  for (const Prism& p : s.prisms) {
    box.extend(Eigen::Vector2d(p.cx - p.radius(), p.cy - p.radius()));
    box.extend(Eigen::Vector2d(p.cx + p.radius(), p.cy + p.radius()));
  }
  box.extend(box.min() - Eigen::Vector2d(1, 1));
  box.extend(box.max() + Eigen::Vector2d(1, 1));
  g.cell = static_cast<float>(std::max(0.5, std::max(box.sizes().x(), box.sizes().y()) / 256.0));
  g.inv_cell = 1.0f / g.cell;
  g.x0 = static_cast<float>(box.min().x());
  g.y0 = static_cast<float>(box.min().y());
  g.nx = static_cast<int>(std::ceil(box.sizes().x() / g.cell));
  g.ny = static_cast<int>(std::ceil(box.sizes().y() / g.cell));
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  std::vector<std::vector<uint16_t>> features(cells);
  auto cover = [&](float cx, float cy, float r, auto&& add) {
    const int i0 = std::max(0, static_cast<int>((cx - r - g.x0) / g.cell));
    const int i1 = std::min(g.nx - 1, static_cast<int>((cx + r - g.x0) / g.cell));
    const int j0 = std::max(0, static_cast<int>((cy - r - g.y0) / g.cell));
    const int j1 = std::min(g.ny - 1, static_cast<int>((cy + r - g.y0) / g.cell));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) add(static_cast<size_t>(j) * g.nx + i);
  };
  for (size_t k = 0; k < s.floor_features.size(); ++k) {
    const FloorFeature& f = s.floor_features[k];
    cover(f.cx, f.cy, std::hypot(f.hx, f.hy), [&](size_t c) { features[c].push_back(static_cast<uint16_t>(k)); });
  }
  g.feature_start.assign(cells + 1, 0);
  g.features.clear();
  for (size_t c = 0; c < cells; ++c) {
    g.feature_start[c] = static_cast<uint32_t>(g.features.size());
    g.features.insert(g.features.end(), features[c].begin(), features[c].end());
  }
  g.feature_start[cells] = static_cast<uint32_t>(g.features.size());
}

}  // namespace detail

using detail::Face;
using detail::FloorFeature;
using detail::Prism;
using GT = sim_ground_truth_t;

Scene::Scene(std::shared_ptr<const detail::SceneData> data) : data_(std::move(data)) {}

const std::string& Scene::name() const { return data_->name; }
uint64_t Scene::seed() const { return data_->seed; }
Environment Scene::environment() const { return data_->environment; }
Pose2D Scene::start_pose() const { return data_->start; }
Eigen::AlignedBox2d Scene::bounds() const { return data_->bounds; }
int Scene::num_solids() const { return static_cast<int>(data_->prisms.size()); }
int Scene::num_pits() const {
  return static_cast<int>(std::count_if(data_->floor_features.begin(), data_->floor_features.end(),
                                        [](const FloorFeature& f) { return f.kind == FloorFeature::kPit; }));
}

namespace {
// Solids the robot cannot drive through: anything standing up from the
// ground and anything low enough to hit its body.
bool blocks_robot(const Prism& p) { return p.z1 > 0.05f && p.z0 < 1.0f; }
}  // namespace

double Scene::clearance(const Eigen::Vector2d& p) const {
  const auto& b = data_->bounds;
  double d =
      std::min(std::min(p.x() - b.min().x(), b.max().x() - p.x()), std::min(p.y() - b.min().y(), b.max().y() - p.y()));
  for (const Prism& q : data_->prisms)
    if (blocks_robot(q)) d = std::min(d, detail::footprint_distance(q, p.x(), p.y()));
  for (const FloorFeature& f : data_->floor_features)
    if (f.kind == FloorFeature::kPit) d = std::min(d, detail::feature_distance(f, p.x(), p.y()));
  return d;
}

double Scene::free_distance(const Eigen::Vector2d& p, double heading, double radius, double max_distance) const {
  const double ux = std::cos(heading), uy = std::sin(heading);
  double best = max_distance;
  // A disc sweeping along the ray hits a footprint when the ray hits the
  // footprint grown by the radius (rectangles grown to rectangles: slightly
  // conservative at corners).
  auto grown_hit = [&](double cx, double cy, double hx, double hy, double c, double s, bool circle, double grow) {
    float t_in, t_out;
    Face face;
    if (circle) {
      detail::circle_interval(static_cast<float>(p.x() - cx), static_cast<float>(p.y() - cy), static_cast<float>(ux),
                              static_cast<float>(uy), static_cast<float>(hx + grow), t_in, t_out);
    } else {
      const double dx = p.x() - cx, dy = p.y() - cy;
      detail::rect_interval(static_cast<float>(c * dx + s * dy), static_cast<float>(-s * dx + c * dy),
                            static_cast<float>(c * ux + s * uy), static_cast<float>(-s * ux + c * uy),
                            static_cast<float>(hx + grow), static_cast<float>(hy + grow), t_in, t_out, face);
    }
    if (t_in <= t_out && t_out > 0) best = std::min(best, std::max(0.0, static_cast<double>(t_in)));
  };
  for (const Prism& q : data_->prisms)
    if (blocks_robot(q)) grown_hit(q.cx, q.cy, q.hx, q.hy, q.cos_yaw, q.sin_yaw, q.shape == Prism::kCircle, radius);
  for (const FloorFeature& f : data_->floor_features)
    if (f.kind == FloorFeature::kPit) grown_hit(f.cx, f.cy, f.hx, f.hy, f.cos_yaw, f.sin_yaw, false, radius);
  const auto& b = data_->bounds;
  auto wall = [&](double pos, double lo, double dir) {
    if (std::abs(dir) < 1e-9) return;
    const double t = (lo - pos) / dir;
    if (t > 0) best = std::min(best, t);
  };
  wall(p.x(), ux > 0 ? b.max().x() - radius : b.min().x() + radius, ux);
  wall(p.y(), uy > 0 ? b.max().y() - radius : b.min().y() + radius, uy);
  return std::max(0.0, best);
}

TruthState Scene::truth_at(const Eigen::Vector2d& p, const TruthQuery& q) const {
  for (const Prism& s : data_->prisms) {
    if (s.z1 <= q.min_height || s.z0 >= q.max_height) continue;
    if (detail::footprint_distance(s, p.x(), p.y()) <= q.radius) return TruthState::kObstacle;
  }
  for (const FloorFeature& f : data_->floor_features)
    if (f.kind == FloorFeature::kPit && detail::feature_distance(f, p.x(), p.y()) <= q.radius) return TruthState::kHole;
  return TruthState::kFree;
}

std::optional<Scene::Hit> Scene::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                         double max_distance) const {
  const Eigen::Vector3d d = direction.normalized();
  const double h = std::hypot(d.x(), d.y());
  std::optional<Hit> best;
  auto consider = [&](double t, int surface, const Eigen::Vector3d& normal) {
    if (t < 0 || t > max_distance || (best && t >= best->distance)) return;
    best = Hit{t, surface, origin + t * d, normal.dot(d) > 0 ? Eigen::Vector3d(-normal) : normal};
  };
  if (h > 1e-9) {
    const double ux = d.x() / h, uy = d.y() / h, slope = d.z() / h;
    for (const Prism& p : data_->prisms) {
      float t_in, t_out;
      Face face;
      detail::footprint_interval(p, static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                                 static_cast<float>(ux), static_cast<float>(uy), t_in, t_out, face);
      if (t_in > t_out || t_out < 0) continue;
      // Entry through the side or through the top / bottom.
      double s_lo = std::max(0.0, static_cast<double>(t_in)), s_hi = t_out;
      Eigen::Vector3d normal;
      if (std::abs(slope) > 1e-12) {
        double za = (p.z0 - origin.z()) / slope, zb = (p.z1 - origin.z()) / slope;
        if (za > zb) std::swap(za, zb);
        if (za > s_lo) {
          s_lo = za;
          normal = Eigen::Vector3d(0, 0, slope > 0 ? -1 : 1);
          face = slope > 0 ? detail::kFaceBottom : detail::kFaceTop;
        }
        s_hi = std::min(s_hi, zb);
      } else if (origin.z() < p.z0 || origin.z() > p.z1) {
        continue;
      }
      if (s_lo > s_hi) continue;
      if (face != detail::kFaceTop && face != detail::kFaceBottom) {
        const Eigen::Vector2d hit(origin.x() + ux * s_lo, origin.y() + uy * s_lo);
        if (p.shape == Prism::kCircle) {
          const Eigen::Vector2d n = (hit - Eigen::Vector2d(p.cx, p.cy)).normalized();
          normal = Eigen::Vector3d(n.x(), n.y(), 0);
        } else {
          const Eigen::Vector2d ax(p.cos_yaw, p.sin_yaw), ay(-p.sin_yaw, p.cos_yaw);
          const Eigen::Vector2d n = (face == detail::kFaceMinusX || face == detail::kFacePlusX) ? ax : ay;
          normal = Eigen::Vector3d(n.x(), n.y(), 0);
        }
      }
      const double z = origin.z() + slope * s_lo;
      const int surface = (p.base_height > 0 && z < p.base_height) ? GT::SURFACE_BASEBOARD : p.surface;
      consider(s_lo / h, surface, normal);
    }
  }
  // Floor (or pit below it) and ceiling.
  if (d.z() < -1e-12) {
    const double t = -origin.z() / d.z();
    const Eigen::Vector3d g = origin + t * d;
    const FloorFeature* pit = nullptr;
    for (const FloorFeature& f : data_->floor_features)
      if (f.kind == FloorFeature::kPit &&
          detail::feature_contains(f, static_cast<float>(g.x()), static_cast<float>(g.y())))
        pit = &f;
    if (!pit) {
      consider(t, GT::SURFACE_FLOOR, Eigen::Vector3d(0, 0, 1));
    } else {
      // March down into the pit: exit through its wall or reach its bottom.
      const double t_bottom = (-pit->depth - origin.z()) / d.z();
      double t_wall = t_bottom;
      for (double tt = t; tt < t_bottom; tt += 0.002) {
        const Eigen::Vector3d q = origin + tt * d;
        if (!detail::feature_contains(*pit, static_cast<float>(q.x()), static_cast<float>(q.y()))) {
          t_wall = tt;
          break;
        }
      }
      consider(t_wall, GT::SURFACE_PIT,
               t_wall < t_bottom ? Eigen::Vector3d(-d.x(), -d.y(), 0).normalized() : Eigen::Vector3d(0, 0, 1));
    }
  } else if (d.z() > 1e-12 && data_->has_ceiling) {
    consider((data_->ceiling_height - origin.z()) / d.z(), GT::SURFACE_CEILING, Eigen::Vector3d(0, 0, -1));
  }
  return best;
}

namespace detail {

std::shared_ptr<SceneData> build_scene(const SceneSpec& spec, uint64_t seed,
                                       const std::function<void(SceneBuilder&)>& before_finish) {
  validate(spec);
  SceneBuilder b(spec, seed);
  build_layout(b);
  for (const ElementSpec& e : spec.elements) b.add_element(e);
  place_obstacles(b);
  place_floor_details(b);
  place_lights(b);
  choose_start(b);
  if (before_finish) before_finish(b);
  return b.finish();
}

}  // namespace detail

Scene generate_scene(const SceneSpec& spec, uint64_t seed) { return Scene(detail::build_scene(spec, seed)); }

}  // namespace ivoa::sim
