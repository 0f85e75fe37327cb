#include "ivoa/causes/cause_finder.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/sim/counterfactual.hpp"
#include "ivoa/sim/messages.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::causes {
namespace {

using GT = sim_ground_truth_t;
using Labels = introspection_labels_t;

// The pose the driver logs is the trajectory's, so any replay error shows
// as a difference far above rounding.
constexpr double kPoseTolerance = 1e-6;  // metres and radians

struct Twin {
  uint8_t phenomenon = 0;
  sim::Simulator simulator;
};

bool is_failure(int8_t label) { return label == Labels::LABEL_FP || label == Labels::LABEL_FN; }

// The state the detector should have given: FP cells are free, FN cells blocked.
int8_t right_state(int8_t label) {
  return label == Labels::LABEL_FP ? obstacle_grid_t::STATE_FREE : obstacle_grid_t::STATE_OBSTACLE;
}

sim::SimulatorConfig render_config(const RigCalibration& rig, uint64_t noise_seed) {
  // Aggregate initialisation: the default rig is never built (and GCC 12
  // sees no dangling temporary in its default initialiser).
  return sim::SimulatorConfig{rig, {}, {},
                              false,  // no depth image: the labels keep the recorded depth verdicts
                              noise_seed};
}

}  // namespace

struct CauseFinder::Impl {
  Impl(const sim::SceneSpec& spec, uint64_t seed, const RigCalibration& rig, SessionTiming t,
       const std::string& detector_name, const stereo::DetectorConfig& detector_config)
      : timing(t),
        factual(sim::generate_scene(spec, seed), render_config(rig, t.noise_seed)),
        trajectory(factual.scene(), seed),
        detector(stereo::make_detector(detector_name, rig, detector_config)) {
    for (const uint8_t p : sim::removable_phenomena())
      if (std::optional<sim::Scene> scene = sim::generate_scene_without(spec, seed, p)) {
        twins.push_back({p, sim::Simulator(std::move(*scene), render_config(rig, t.noise_seed))});
        testable |= p;
      }
    if (twins.size() >= 2)
      all_removed = std::make_unique<sim::Simulator>(*sim::generate_scene_without(spec, seed, testable),
                                                     render_config(rig, t.noise_seed));
  }

  sim::RenderRequest request_for(const Labels& labels, const sim::Pose2D& recorded_pose);
  // The detector's state for each failure cell on a frame rendered by `simulator`.
  std::vector<int8_t> states(const sim::Simulator& simulator, const sim::RenderRequest& request,
                             const Labels& labels, const std::vector<int32_t>& cells, int32_t pixelformat);

  SessionTiming timing;
  sim::Simulator factual;
  sim::Trajectory trajectory;
  std::unique_ptr<stereo::ObstacleDetector> detector;
  std::vector<Twin> twins;
  std::unique_ptr<sim::Simulator> all_removed;  // every testable phenomenon taken away (two or more)
  uint8_t testable = 0;
};

sim::RenderRequest CauseFinder::Impl::request_for(const Labels& labels, const sim::Pose2D& recorded_pose) {
  const double index = std::round(static_cast<double>(labels.utime - timing.start_utime) * timing.rate_hz * 1e-6);
  if (index < 0)
    throw ReplayError("frame " + std::to_string(labels.utime) + " is before the session's start utime " +
                      std::to_string(timing.start_utime));
  const double t = index / timing.rate_hz;
  sim::RenderRequest request;
  request.stereo_pose = trajectory.pose_at(t);
  request.depth_pose = request.stereo_pose;
  request.frame_index = static_cast<uint64_t>(index);
  request.motion = trajectory.twist_at(t);
  const sim::Pose2D& p = request.stereo_pose;
  if (std::abs(p.x - recorded_pose.x) > kPoseTolerance || std::abs(p.y - recorded_pose.y) > kPoseTolerance ||
      std::abs(p.yaw - recorded_pose.yaw) > kPoseTolerance)
    throw ReplayError("frame " + std::to_string(labels.utime) + ": the recorded robot pose (" +
                      std::to_string(recorded_pose.x) + ", " + std::to_string(recorded_pose.y) + ", " +
                      std::to_string(recorded_pose.yaw) + ") is not the trajectory's at frame " +
                      std::to_string(request.frame_index) + " (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                      ", " + std::to_string(p.yaw) + "): another --rate, or not recorded by the simulator driver?");
  return request;
}

std::vector<int8_t> CauseFinder::Impl::states(const sim::Simulator& simulator, const sim::RenderRequest& request,
                                              const Labels& labels, const std::vector<int32_t>& cells,
                                              int32_t pixelformat) {
  const sim::SimFrame frame = simulator.render(request);
  // Through the message, as the live detector received it (Bayer mosaic and demosaicing included).
  const stereo_image_t msg = sim::make_stereo_message(frame, labels.utime, 0, pixelformat);
  detector->set_frame(decode_image(msg.left), decode_image(msg.right));
  std::vector<int8_t> out;
  out.reserve(cells.size());
  for (const int32_t c : cells) {
    const auto i = static_cast<size_t>(c);
    out.push_back(stereo::to_state(detector->check(labels.x[i], labels.y[i], labels.safety_radius)));
  }
  return out;
}

CauseFinder::CauseFinder(const sim::SceneSpec& spec, uint64_t seed, const RigCalibration& rig, SessionTiming timing,
                         const std::string& detector, const stereo::DetectorConfig& detector_config)
    : impl_(std::make_unique<Impl>(spec, seed, rig, timing, detector, detector_config)) {}

CauseFinder::~CauseFinder() = default;

uint8_t CauseFinder::testable() const { return impl_->testable; }

std::vector<CellCause> CauseFinder::explain(const introspection_labels_t& labels, const sim::Pose2D& pose,
                                            int32_t pixelformat) {
  std::vector<int32_t> cells;
  for (int32_t c = 0; c < labels.num_cells; ++c)
    if (is_failure(labels.label[static_cast<size_t>(c)])) cells.push_back(c);
  if (cells.empty()) return {};
  const sim::RenderRequest request = impl_->request_for(labels, pose);
  const std::vector<int8_t> replayed = impl_->states(impl_->factual, request, labels, cells, pixelformat);
  std::vector<CellCause> out(cells.size());
  for (size_t k = 0; k < cells.size(); ++k) {
    const auto i = static_cast<size_t>(cells[k]);
    out[k] = {cells[k], labels.label[i], labels.stereo_state[i], replayed[k], impl_->testable, 0, false};
  }
  for (const Twin& twin : impl_->twins) {
    const std::vector<int8_t> without = impl_->states(twin.simulator, request, labels, cells, pixelformat);
    for (size_t k = 0; k < cells.size(); ++k)
      if (out[k].reproduced() && without[k] == right_state(out[k].label)) out[k].causes |= twin.phenomenon;
  }
  const bool unexplained = std::any_of(out.begin(), out.end(), [](const CellCause& c) { return c.reproduced() && !c.causes; });
  if (impl_->all_removed && unexplained) {
    const std::vector<int8_t> without = impl_->states(*impl_->all_removed, request, labels, cells, pixelformat);
    for (size_t k = 0; k < cells.size(); ++k)
      out[k].jointly = out[k].reproduced() && !out[k].causes && without[k] == right_state(out[k].label);
  }
  return out;
}

std::string phenomena_names(uint8_t bits) {
  static const std::pair<uint8_t, const char*> kNames[] = {
      {GT::PHENOMENON_REFLECTION, "reflection"}, {GT::PHENOMENON_TEXTURELESS, "textureless"},
      {GT::PHENOMENON_GLARE, "glare"},           {GT::PHENOMENON_DARK_STRIPE, "dark stripe"},
      {GT::PHENOMENON_REPETITIVE, "repetitive"}, {GT::PHENOMENON_LOW_LIGHT, "low light"},
      {GT::PHENOMENON_SATURATED, "saturated"}};
  if (bits == 0) return "none found";
  std::string out;
  for (const auto& [bit, name] : kNames)
    if (bits & bit) out += (out.empty() ? "" : "+") + std::string(name);
  return out;
}

std::string describe(const CellCause& c) {
  if (!c.reproduced()) return "not reproduced";
  if (c.causes) return phenomena_names(c.causes);
  return c.jointly ? "together: " + phenomena_names(c.tested) : "none found";
}

}  // namespace ivoa::causes
