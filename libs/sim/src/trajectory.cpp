#include "ivoa/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <deque>

#include "rng.hpp"

namespace ivoa::sim {
namespace {

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

struct Sample {
  Pose2D pose;
  Twist2D twist;
};

enum class Mode { kCruise, kApproach, kTurnAway };

}  // namespace

// How much of the planned path is kept behind the latest time asked for.
// An older time is planned again from the start (the plan is deterministic),
// so a session of hours holds a minute of samples, not all of them.
constexpr double kKeptSeconds = 60.0;

struct Trajectory::Impl {
  Impl(Scene s, uint64_t seed, TrajectoryConfig c, Pose2D start)
      : scene(std::move(s)), config(c), rng_seed(hash_combine(seed, hash_string("trajectory"))), start_pose(start) {
    restart();
    min_clearance = clearance(start);
  }

  // Back to the start of the plan: every field the plan changes as it goes
  // is set here, so planning again gives the same path.
  void restart() {
    rng = Rng(rng_seed);
    samples.assign(1, {start_pose, {}});
    first_step = 0;
    start_cruise();
    approach_heading = turn_target = turn_time = 0;
    turn_direction = 1;
  }

  double clearance(const Pose2D& p) const { return scene.clearance({p.x, p.y}) - config.robot_radius; }
  double free_ahead(const Pose2D& p, double heading, double max = 6.0) const {
    return scene.free_distance({p.x, p.y}, heading, config.robot_radius, max);
  }

  void start_cruise() {
    mode = Mode::kCruise;
    leg_time = rng.uniform(1.5, 4.0);
    target_speed = rng.uniform(config.min_speed, config.max_speed);
    target_yaw_rate = rng.uniform(-0.35, 0.35);
    gap = rng.uniform(config.approach_gap_min, config.approach_gap_max);
    approach_pending = rng.chance(config.approach_probability);
    approach_delay = rng.uniform(0.3, 1.5);
  }

  // Heading (within +-70 deg of the current one) of the nearest thing ahead
  // within 4 m, if any.
  bool nearest_obstacle_heading(const Pose2D& p, double& heading) const {
    double best = 4.0;
    bool found = false;
    for (int k = -7; k <= 7; ++k) {
      const double h = wrap(p.yaw + k * (70.0 / 7.0) * M_PI / 180.0);
      const double f = free_ahead(p, h, 4.0);
      if (f < best - 1e-6) {
        best = f;
        heading = h;
        found = true;
      }
    }
    return found && best > gap + 0.05;
  }

  void start_turn_away(const Pose2D& p) {
    mode = Mode::kTurnAway;
    // Prefer open directions, with randomness so the robot does not oscillate.
    std::vector<double> weights, headings;
    for (int k = 0; k < 16; ++k) {
      const double h = wrap(p.yaw + (k + 0.5) * M_PI / 8);
      const double f = free_ahead(p, h);
      headings.push_back(h);
      weights.push_back(f > 1.0 ? f * f : 0.01 * f);
    }
    turn_target = headings[rng.weighted(weights)];
    turn_direction = wrap(turn_target - p.yaw) >= 0 ? 1.0 : -1.0;
    turn_time = 0;
  }

  // Commanded speed and yaw rate for the next step.
  void command(const Pose2D& p, double& v_cmd, double& w_cmd) {
    const double dt = config.step;
    const double ahead = free_ahead(p, p.yaw);
    switch (mode) {
      case Mode::kCruise: {
        leg_time -= dt;
        approach_delay -= dt;
        double heading;
        if (approach_pending && approach_delay <= 0 && nearest_obstacle_heading(p, heading)) {
          mode = Mode::kApproach;
          approach_heading = heading;
          target_speed = rng.uniform(0.25, 0.45);
          approach_pending = false;
        } else if (ahead <= gap) {
          start_turn_away(p);
        } else if (leg_time <= 0) {
          start_cruise();
        }
        v_cmd = std::min(target_speed, 0.8 * (ahead - gap) + 0.05);
        w_cmd = target_yaw_rate;
        break;
      }
      case Mode::kApproach: {
        const double error = wrap(approach_heading - p.yaw);
        w_cmd = std::clamp(2.0 * error, -config.max_yaw_rate, config.max_yaw_rate);
        v_cmd = std::min(target_speed, 0.8 * (ahead - gap) + 0.05);
        if (ahead <= gap + 0.01) start_turn_away(p);
        break;
      }
      case Mode::kTurnAway: {
        turn_time += dt;
        const double error = wrap(turn_target - p.yaw);
        w_cmd = turn_direction * std::min(config.max_yaw_rate, 0.3 + 1.5 * std::abs(error));
        v_cmd = 0;
        if ((std::abs(error) < 0.12 && ahead > gap + 0.3) || turn_time > 12.0) {
          start_cruise();
          approach_delay = rng.uniform(1.0, 2.5);
        }
        break;
      }
    }
    v_cmd = std::max(0.0, v_cmd);
  }

  void step() {
    const Sample& last = samples.back();
    double v_cmd = 0, w_cmd = 0;
    command(last.pose, v_cmd, w_cmd);
    const double dt = config.step;
    Twist2D tw = last.twist;
    tw.v += std::clamp(v_cmd - tw.v, -config.acceleration * dt, config.acceleration * dt);
    tw.omega += std::clamp(w_cmd - tw.omega, -config.yaw_acceleration * dt, config.yaw_acceleration * dt);
    Pose2D next = last.pose;
    next.yaw = wrap(next.yaw + tw.omega * dt);
    next.x += tw.v * dt * std::cos(next.yaw);
    next.y += tw.v * dt * std::sin(next.yaw);
    // Like a careful operator: stop once the footprint comes within this
    // leg's gap (0.3-0.5 m) of anything, in any direction, and turn away.
    // And never, whatever the mode, closer than min_clearance.
    const double c = clearance(next), c_now = clearance(last.pose);
    const bool closing = c < c_now - 1e-9;
    if (closing && (c < config.min_clearance || (mode != Mode::kTurnAway && c < gap))) {
      next.x = last.pose.x;
      next.y = last.pose.y;
      tw.v = 0;
      if (mode != Mode::kTurnAway) start_turn_away(next);
    }
    min_clearance = std::min(min_clearance, clearance(next));
    samples.push_back({next, tw});
  }

  Sample at(double t) {
    t = std::max(0.0, t);
    const double pos = t / config.step;
    const size_t i = static_cast<size_t>(pos);
    if (i < first_step) restart();
    while (first_step + samples.size() < i + 2) {
      step();
      forget_before(i);  // as it goes: planning hours ahead holds a minute too
    }
    const Sample& a = samples[i - first_step];
    const Sample& b = samples[i - first_step + 1];
    const double f = pos - static_cast<double>(i);
    Sample s;
    s.pose.x = a.pose.x + (b.pose.x - a.pose.x) * f;
    s.pose.y = a.pose.y + (b.pose.y - a.pose.y) * f;
    s.pose.yaw = wrap(a.pose.yaw + wrap(b.pose.yaw - a.pose.yaw) * f);
    s.twist.v = a.twist.v + (b.twist.v - a.twist.v) * f;
    s.twist.omega = a.twist.omega + (b.twist.omega - a.twist.omega) * f;
    return s;
  }

  // Drops the samples more than kKeptSeconds before step i, but never the
  // newest, which the next step starts from.
  void forget_before(size_t i) {
    const size_t kept = static_cast<size_t>(kKeptSeconds / config.step);
    while (first_step + kept < i && samples.size() > 1) {
      samples.pop_front();
      ++first_step;
    }
  }

  Scene scene;
  TrajectoryConfig config;
  uint64_t rng_seed;
  Pose2D start_pose;
  Rng rng{0};
  std::deque<Sample> samples;  // samples[k] is step first_step + k
  size_t first_step = 0;
  double min_clearance = 1e9;  // over every step planned, so not reset by restart()
  Mode mode = Mode::kCruise;
  double leg_time = 0, target_speed = 0, target_yaw_rate = 0, gap = 0.4;
  bool approach_pending = false;
  double approach_delay = 0, approach_heading = 0;
  double turn_target = 0, turn_direction = 1, turn_time = 0;
};

Trajectory::Trajectory(Scene scene, uint64_t seed, TrajectoryConfig config, std::optional<Pose2D> start) {
  const Pose2D s = start ? *start : scene.start_pose();
  impl_ = std::make_unique<Impl>(std::move(scene), seed, config, s);
}
Trajectory::~Trajectory() = default;
Trajectory::Trajectory(Trajectory&&) noexcept = default;
Trajectory& Trajectory::operator=(Trajectory&&) noexcept = default;

Pose2D Trajectory::pose_at(double t) { return impl_->at(t).pose; }
Twist2D Trajectory::twist_at(double t) { return impl_->at(t).twist; }
double Trajectory::min_clearance() const { return impl_->min_clearance; }
std::size_t Trajectory::steps_held() const { return impl_->samples.size(); }
const TrajectoryConfig& Trajectory::config() const { return impl_->config; }

}  // namespace ivoa::sim
