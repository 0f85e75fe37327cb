#pragma once
// A joystick-like drive through a scene: cruises at varied speeds and
// headings, often steers at an obstacle or wall, stops 0.3-0.5 m short of it
// and turns away. Collision-free (the footprint never comes closer than
// min_clearance to anything) and deterministic for a scene and seed.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/scene.hpp"

namespace ivoa::sim {

struct TrajectoryConfig {
  double robot_radius = 0.28;         // metres, disc around the robot origin (Jackal-sized)
  double min_speed = 0.2;             // m/s while cruising
  double max_speed = 0.6;             // m/s
  double max_yaw_rate = 0.9;          // rad/s
  double acceleration = 0.6;          // m/s^2
  double yaw_acceleration = 2.5;      // rad/s^2
  double approach_probability = 0.6;  // chance, when a new cruise leg starts, to head for the nearest obstacle
  double approach_gap_min = 0.30;     // metres between footprint and obstacle where an approach stops
  double approach_gap_max = 0.50;
  double min_clearance = 0.10;  // metres, hard limit between footprint and anything
  double step = 0.02;           // s, integration step
};

class Trajectory {
 public:
  // start: the scene's start pose unless given.
  Trajectory(Scene scene, uint64_t seed, TrajectoryConfig config = {}, std::optional<Pose2D> start = {});
  ~Trajectory();
  Trajectory(Trajectory&&) noexcept;
  Trajectory& operator=(Trajectory&&) noexcept;

  // Pose and velocity t seconds after the start (t >= 0). Plans ahead as far
  // as needed and holds the last minute of the plan before t: a t earlier
  // than that is planned again from the start, so the same t always gives
  // the same answer and a session of hours holds a minute of samples.
  Pose2D pose_at(double t);
  Twist2D twist_at(double t);
  // Smallest footprint clearance (metres) over the path planned so far.
  double min_clearance() const;
  // How many planned steps are held (one each TrajectoryConfig::step).
  std::size_t steps_held() const;
  const TrajectoryConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ivoa::sim
