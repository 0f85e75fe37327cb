#pragma once
// Why did the stereo detector fail on a simulated frame? For each failure
// cell (FP, FN) of a frame's recorded labels, CauseFinder renders the frame
// again exactly as the simulator driver did, and once more per removable
// phenomenon with that phenomenon taken out of the scene, and re-runs the
// detector on the cell. A phenomenon *causes* the failure when taking it
// away turns the detector's verdict into the right one. Where no single
// phenomenon does, a last twin without all of them tells whether they cause
// it together.
//
// The same frames can also be checked by the detector with other settings
// (DetectorVariant): where a variant gives the right verdict on a failure,
// that setting would have avoided it, and what the variant gets wrong on the
// cells the detector got right is the price. A setting that fixes and
// breaks at similar rates only shifts the detector's bias.
#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ivoa/core/calibration.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/sim/pose.hpp"
#include "ivoa/sim/scene_spec.hpp"
#include "ivoa/stereo/config.hpp"

namespace ivoa::causes {

// Thrown when a frame cannot be reproduced (its pose is not the trajectory's
// at the time the session's rate gives): what() names the frame.
class ReplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws std::invalid_argument, naming the frame and cell, for labels that
// cannot be explained: a label outside -1..3 (it indexes the tallies), a
// cell or safety radius that is not a finite distance.
void check_labels(const introspection_labels_t& labels);

// How the simulator driver recorded the session (its defaults are the driver's).
struct SessionTiming {
  int64_t start_utime = 0;  // utime of frame 0
  double rate_hz = 2.0;     // frames per second of session time (the driver's --rate)
  uint64_t noise_seed = 0;  // the driver's --noise-seed
};

// The driver's --rate from the times of its frames, frame 0's first (in
// order, at least two; else 1 Hz, which a one-frame session does not use).
// It stamps frame k at start + k / rate, rounded to the microsecond, but
// in real time it skips the frames it is late for (and a logger can drop
// some): a gap may span several periods, never less than one. So the
// period is the longest that every gap is a whole number of (the shortest
// gap, or up to a 16th of it when no two frames follow each other), and
// the span counted in periods gives the rate. Gaps that are all even
// multiples of the period cannot tell it from twice the period (the poses
// agree then; the noise, drawn per frame index, does not).
double rate_from_frame_times(const std::vector<int64_t>& utimes);
// Whether every gap between the frame times is a whole number of periods
// of `rate_hz` (to the microsecond rounding): a --rate that can be the
// driver's, though a multiple of it fits too.
bool frame_times_fit_rate(const std::vector<int64_t>& utimes, double rate_hz);

// Other settings of the same detector to try on the factual frames, e.g.
// "full resolution" (--rect_scale 1). At most 8.
struct DetectorVariant {
  std::string name;  // a CSV field: no ',', '"', '+' or line breaks
  stereo::DetectorConfig config;
};

struct CellCause {
  int32_t cell = 0;           // index into the labels message
  int8_t label = 0;           // LABEL_FP or LABEL_FN
  int8_t stereo_state = 0;    // recorded obstacle_grid_t::STATE_*
  int8_t replayed_state = 0;  // the detector on the re-rendered frame
  uint8_t tested = 0;         // PHENOMENON_* bits the scene carries (a twin was rendered)
  uint8_t causes = 0;         // PHENOMENON_* bits whose removal (each alone) makes the verdict right
  bool jointly = false;       // no single removal does, removing all `tested` together does
  uint8_t fixed_by = 0;       // bit i: variants[i] gives the right verdict on the factual frame
  bool reproduced() const { return replayed_state == stereo_state; }
};

// What one variant says on every labelled cell of the frames explained so
// far (frames with failures only: others are not rendered), by the
// recorded label (introspection_labels_t::LABEL_*, TP 0 .. FN 3). Right:
// the state the depth monitor found (TP, FN: obstacle; TN, FP: free);
// wrong: the other one; the rest gave no verdict.
struct VariantTally {
  std::array<int64_t, 4> cells{}, right{}, wrong{};
};

class CauseFinder {
 public:
  // Generates the scene and its twins once. Throws SceneSpecError or
  // std::invalid_argument (detector name or config, a bad variant).
  CauseFinder(const sim::SceneSpec& spec, uint64_t seed, const RigCalibration& rig, SessionTiming timing,
              const std::string& detector, const stereo::DetectorConfig& detector_config,
              const std::vector<DetectorVariant>& variants = {});
  ~CauseFinder();

  // The failure cells of one frame's labels, in cell order (none: nothing
  // rendered). `pose` is the pose recorded with the frame: a mismatch with
  // the trajectory, or labels check_labels refuses, throw ReplayError. `pixelformat` is the recorded
  // stereo pair's, so the detector sees the same demosaiced image.
  std::vector<CellCause> explain(const introspection_labels_t& labels, const sim::Pose2D& pose, int32_t pixelformat);

  // The PHENOMENON_* bits this scene carries and twins exist for.
  uint8_t testable() const;
  // One per variant, in the constructor's order.
  const std::vector<VariantTally>& variant_tallies() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Throws std::invalid_argument unless the name can be a CSV field.
void check_variant_name(const std::string& name);
// "full resolution+narrow window" for bits 0 and 1; "" for none.
std::string variant_names(const std::vector<DetectorVariant>& variants, uint8_t bits);

// "reflection+dark stripe", "none found" for 0: names of PHENOMENON_* bits.
std::string phenomena_names(uint8_t bits);
// What caused a cell's failure: its causes' names, "together: <tested>"
// when only removing all of them helps, "none found", or "not reproduced".
std::string describe(const CellCause& cause);

}  // namespace ivoa::causes
