#include "ivoa/causes/cause_finder.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "ivoa/core/grid_messages.hpp"
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
constexpr double kPoseTolerance = 1e-6;          // metres and radians
constexpr double kLongestSessionS = 4 * 3600.0;  // the simulator driver's sessions run minutes

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
  return sim::SimulatorConfig{rig,
                              {},
                              {},
                              false,  // no depth image: the labels keep the recorded depth verdicts
                              noise_seed};
}

struct Variant {
  std::string name;
  std::unique_ptr<stereo::ObstacleDetector> detector;
};

// The true state of a labelled cell: the depth monitor's (TP, FN: obstacle).
int8_t true_state(int8_t label) {
  return label == Labels::LABEL_TP || label == Labels::LABEL_FN ? obstacle_grid_t::STATE_OBSTACLE
                                                                : obstacle_grid_t::STATE_FREE;
}

}  // namespace

struct CauseFinder::Impl {
  Impl(const sim::SceneSpec& spec, uint64_t seed, const RigCalibration& rig, SessionTiming t,
       const std::string& detector_name, const stereo::DetectorConfig& detector_config,
       const std::vector<DetectorVariant>& variant_specs)
      : timing(t),
        factual(sim::generate_scene(spec, seed), render_config(rig, t.noise_seed)),
        trajectory(factual.scene(), seed),
        detector(stereo::make_detector(detector_name, rig, detector_config)) {
    if (variant_specs.size() > 8) throw std::invalid_argument("at most 8 detector variants");
    for (const DetectorVariant& v : variant_specs) {
      check_variant_name(v.name);
      variants.push_back({v.name, stereo::make_detector(detector_name, rig, v.config)});
    }
    tallies.resize(variants.size());
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
  // Renders the frame and gives it to `detectors` as the live detector
  // received it (through the message: Bayer mosaic and demosaicing included).
  void show(const sim::Simulator& simulator, const sim::RenderRequest& request, const Labels& labels,
            int32_t pixelformat, const std::vector<stereo::ObstacleDetector*>& detectors) const;
  // The state `d` gives each of `cells` on the frame it was last shown.
  static std::vector<int8_t> states(stereo::ObstacleDetector& d, const Labels& labels,
                                    const std::vector<int32_t>& cells);
  // The variants on the factual frame: marks the failures each fixes and tallies every labelled cell.
  void try_variants(const Labels& labels, std::vector<CellCause>& failures);

  SessionTiming timing;
  sim::Simulator factual;
  sim::Trajectory trajectory;
  std::unique_ptr<stereo::ObstacleDetector> detector;
  std::vector<Variant> variants;
  std::vector<VariantTally> tallies;
  std::vector<Twin> twins;
  std::unique_ptr<sim::Simulator> all_removed;  // every testable phenomenon taken away (two or more)
  uint8_t testable = 0;
};

sim::RenderRequest CauseFinder::Impl::request_for(const Labels& labels, const sim::Pose2D& recorded_pose) {
  const double index = std::round(static_cast<double>(labels.utime - timing.start_utime) * timing.rate_hz * 1e-6);
  if (index < 0)
    throw ReplayError("frame " + std::to_string(labels.utime) + " is before the session's start utime " +
                      std::to_string(timing.start_utime));
  // The trajectory is stepped from the start to the frame: a utime far
  // beyond any session would take it hours.
  if (index / timing.rate_hz > kLongestSessionS)
    throw ReplayError("frame " + std::to_string(labels.utime) + " is " +
                      std::to_string(static_cast<int64_t>(index / timing.rate_hz)) +
                      " s after the session's start utime " + std::to_string(timing.start_utime) +
                      ": longer than any simulated session (" + std::to_string(static_cast<int>(kLongestSessionS)) +
                      " s), skipped");
  const double t = index / timing.rate_hz;
  sim::RenderRequest request;
  request.stereo_pose = trajectory.pose_at(t);
  request.depth_pose = request.stereo_pose;
  request.frame_index = static_cast<uint64_t>(index);
  request.motion = trajectory.twist_at(t);
  const sim::Pose2D& p = request.stereo_pose;
  // Written as "not within" so that a NaN recorded pose is refused too.
  if (!(std::abs(p.x - recorded_pose.x) <= kPoseTolerance && std::abs(p.y - recorded_pose.y) <= kPoseTolerance &&
        std::abs(p.yaw - recorded_pose.yaw) <= kPoseTolerance))
    throw ReplayError("frame " + std::to_string(labels.utime) + ": the recorded robot pose (" +
                      std::to_string(recorded_pose.x) + ", " + std::to_string(recorded_pose.y) + ", " +
                      std::to_string(recorded_pose.yaw) + ") is not the trajectory's at frame " +
                      std::to_string(request.frame_index) + " (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                      ", " + std::to_string(p.yaw) + "): another --rate, or not recorded by the simulator driver?");
  return request;
}

void CauseFinder::Impl::show(const sim::Simulator& simulator, const sim::RenderRequest& request, const Labels& labels,
                             int32_t pixelformat, const std::vector<stereo::ObstacleDetector*>& detectors) const {
  const sim::SimFrame frame = simulator.render(request);
  const stereo_image_t msg = sim::make_stereo_message(frame, labels.utime, 0, pixelformat);
  const cv::Mat left = decode_image(msg.left), right = decode_image(msg.right);
  for (stereo::ObstacleDetector* d : detectors) d->set_frame(left, right);
}

std::vector<int8_t> CauseFinder::Impl::states(stereo::ObstacleDetector& d, const Labels& labels,
                                              const std::vector<int32_t>& cells) {
  std::vector<int8_t> out;
  out.reserve(cells.size());
  for (const int32_t c : cells) {
    const auto i = static_cast<size_t>(c);
    out.push_back(stereo::to_state(d.check(labels.x[i], labels.y[i], labels.safety_radius)));
  }
  return out;
}

void CauseFinder::Impl::try_variants(const Labels& labels, std::vector<CellCause>& failures) {
  std::vector<int32_t> labelled;
  for (int32_t c = 0; c < labels.num_cells; ++c)
    if (labels.label[static_cast<size_t>(c)] != Labels::LABEL_NONE) labelled.push_back(c);
  for (size_t v = 0; v < variants.size(); ++v) {
    const std::vector<int8_t> said = states(*variants[v].detector, labels, labelled);
    std::vector<int8_t> said_at(static_cast<size_t>(labels.num_cells), obstacle_grid_t::STATE_UNKNOWN);
    for (size_t k = 0; k < labelled.size(); ++k) {
      const int8_t label = labels.label[static_cast<size_t>(labelled[k])];
      const auto l = static_cast<size_t>(label);
      const int8_t truth = true_state(label);
      ++tallies[v].cells[l];
      tallies[v].right[l] += said[k] == truth;
      tallies[v].wrong[l] += said[k] != truth && said[k] != obstacle_grid_t::STATE_UNKNOWN;
      said_at[static_cast<size_t>(labelled[k])] = said[k];
    }
    for (CellCause& f : failures)
      if (f.reproduced() && said_at[static_cast<size_t>(f.cell)] == right_state(f.label))
        f.fixed_by |= static_cast<uint8_t>(1u << v);
  }
}

CauseFinder::CauseFinder(const sim::SceneSpec& spec, uint64_t seed, const RigCalibration& rig, SessionTiming timing,
                         const std::string& detector, const stereo::DetectorConfig& detector_config,
                         const std::vector<DetectorVariant>& variants)
    : impl_(std::make_unique<Impl>(spec, seed, rig, timing, detector, detector_config, variants)) {}

CauseFinder::~CauseFinder() = default;

uint8_t CauseFinder::testable() const { return impl_->testable; }

const std::vector<VariantTally>& CauseFinder::variant_tallies() const { return impl_->tallies; }

void check_labels(const introspection_labels_t& m) {
  if (const std::string error = labels_content_error(m); !error.empty())
    throw std::invalid_argument("labels at utime " + std::to_string(m.utime) + ": " + error);
}

std::vector<CellCause> CauseFinder::explain(const introspection_labels_t& labels, const sim::Pose2D& pose,
                                            int32_t pixelformat) {
  try {
    check_labels(labels);
  } catch (const std::invalid_argument& e) {
    throw ReplayError(e.what());
  }
  std::vector<int32_t> cells;
  for (int32_t c = 0; c < labels.num_cells; ++c)
    if (is_failure(labels.label[static_cast<size_t>(c)])) cells.push_back(c);
  if (cells.empty()) return {};
  const sim::RenderRequest request = impl_->request_for(labels, pose);
  std::vector<stereo::ObstacleDetector*> on_factual{impl_->detector.get()};
  for (const Variant& v : impl_->variants) on_factual.push_back(v.detector.get());
  impl_->show(impl_->factual, request, labels, pixelformat, on_factual);
  const std::vector<int8_t> replayed = Impl::states(*impl_->detector, labels, cells);
  std::vector<CellCause> out(cells.size());
  for (size_t k = 0; k < cells.size(); ++k) {
    const auto i = static_cast<size_t>(cells[k]);
    out[k] = {cells[k], labels.label[i], labels.stereo_state[i], replayed[k], impl_->testable, 0, false, 0};
  }
  impl_->try_variants(labels, out);
  for (const Twin& twin : impl_->twins) {
    impl_->show(twin.simulator, request, labels, pixelformat, {impl_->detector.get()});
    const std::vector<int8_t> without = Impl::states(*impl_->detector, labels, cells);
    for (size_t k = 0; k < cells.size(); ++k)
      if (out[k].reproduced() && without[k] == right_state(out[k].label)) out[k].causes |= twin.phenomenon;
  }
  const bool unexplained =
      std::any_of(out.begin(), out.end(), [](const CellCause& c) { return c.reproduced() && !c.causes; });
  if (impl_->all_removed && unexplained) {
    impl_->show(*impl_->all_removed, request, labels, pixelformat, {impl_->detector.get()});
    const std::vector<int8_t> without = Impl::states(*impl_->detector, labels, cells);
    for (size_t k = 0; k < cells.size(); ++k)
      out[k].jointly = out[k].reproduced() && !out[k].causes && without[k] == right_state(out[k].label);
  }
  return out;
}

void check_variant_name(const std::string& name) {
  if (name.empty() || name.find_first_of(",\"+\r\n") != std::string::npos)
    throw std::invalid_argument("detector variant name '" + name +
                                "': must be non-empty, without ',', '\"', '+' or line breaks (a CSV field)");
}

std::string variant_names(const std::vector<DetectorVariant>& variants, uint8_t bits) {
  std::string out;
  for (size_t v = 0; v < variants.size(); ++v)
    if (bits & (1u << v)) out += (out.empty() ? "" : "+") + variants[v].name;
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

namespace {

// Whether every gap is a whole number of `period`s, to the frame times'
// rounding: each time is within 0.5 us, so a gap within 1 us, and n periods
// of a period known to `period_error_us` are off by n times that more.
bool gaps_are_whole_periods(const std::vector<int64_t>& utimes, double period, double period_error_us) {
  for (size_t i = 1; i < utimes.size(); ++i) {
    const double gap = static_cast<double>(utimes[i] - utimes[i - 1]);
    const double n = std::round(gap / period);
    if (n < 1 || std::abs(gap - n * period) > 1.5 + n * period_error_us) return false;
  }
  return true;
}

}  // namespace

bool frame_times_fit_rate(const std::vector<int64_t>& utimes, double rate_hz) {
  return gaps_are_whole_periods(utimes, 1e6 / rate_hz, 0.0);
}

double rate_from_frame_times(const std::vector<int64_t>& utimes) {
  int64_t shortest = 0;
  for (size_t i = 1; i < utimes.size(); ++i) {
    const int64_t gap = utimes[i] - utimes[i - 1];
    if (gap > 0 && (shortest == 0 || gap < shortest)) shortest = gap;
  }
  if (shortest == 0) return 1.0;
  // The longest period every gap is a multiple of: the shortest gap itself,
  // or a half, a third... of it when no two frames follow each other.
  constexpr int kMostPeriodsInTheShortestGap = 16;
  double period = static_cast<double>(shortest);
  for (int parts = 1; parts <= kMostPeriodsInTheShortestGap; ++parts)
    // The shortest gap is within 1 us: cut in parts, each within 1 / parts.
    if (gaps_are_whole_periods(utimes, static_cast<double>(shortest) / parts, 1.0 / parts)) {
      period = static_cast<double>(shortest) / parts;
      break;
    }
  double periods = 0;
  for (size_t i = 1; i < utimes.size(); ++i)
    periods += std::round(static_cast<double>(utimes[i] - utimes[i - 1]) / period);
  return periods * 1e6 / static_cast<double>(utimes.back() - utimes.front());
}

}  // namespace ivoa::causes
