#pragma once
// A generated scene: static geometry (a ground plane, vertical prisms standing
// on it or floating above it, pits below it, an optional ceiling), materials
// with their texture maps, and lights. Immutable and cheap to copy (shared).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "ivoa/sim/truth.hpp"

namespace ivoa::sim {
namespace detail {
struct SceneData;
}

class Scene {
 public:
  // The first surface a ray meets (geometry only: no reflections, no noise).
  struct Hit {
    double distance = 0;     // metres along the ray
    int surface = 0;         // sim_ground_truth_t::SURFACE_*
    Eigen::Vector3d point;   // world frame
    Eigen::Vector3d normal;  // world frame, facing the ray
  };

  explicit Scene(std::shared_ptr<const detail::SceneData> data);

  const std::string& name() const;
  uint64_t seed() const;
  Environment environment() const;
  Pose2D start_pose() const;
  // Where the robot may drive (world frame, metres).
  Eigen::AlignedBox2d bounds() const;

  // Horizontal distance from a world point to the nearest solid that stands
  // above 0.05 m, pit opening or the bounds (negative inside a footprint).
  double clearance(const Eigen::Vector2d& p) const;
  // Distance a disc of `radius` can move from p along `heading` (rad) before
  // it touches a solid, pit or the bounds; at most max_distance.
  double free_distance(const Eigen::Vector2d& p, double heading, double radius, double max_distance) const;
  // Footprint occupancy at a world point (see truth.hpp for the definition).
  TruthState truth_at(const Eigen::Vector2d& p, const TruthQuery& query = {}) const;
  // First surface along origin + t * direction (world frame), t <= max_distance.
  std::optional<Hit> raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double max_distance = 100.0) const;

  int num_solids() const;
  int num_pits() const;
  const detail::SceneData& data() const { return *data_; }

 private:
  std::shared_ptr<const detail::SceneData> data_;
};

// Builds a scene from a spec; the same spec and seed always give the same scene.
// Throws SceneSpecError for an invalid spec.
Scene generate_scene(const SceneSpec& spec, uint64_t seed);

}  // namespace ivoa::sim
