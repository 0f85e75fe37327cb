#pragma once
// One interface for the stereo obstacle detectors IVOA introspects: "is the
// robot's footprint of radius r around the ground point (x, y, 0) free?".
// "jppc" is JPP-C (sparse checks, convex world), "dense" is SGBM disparity
// classified by height. The stereo detector process and the offline dataset
// tool both use make_detector() + set_frame() + evaluate(). A detector is
// not thread-safe; make one per thread.
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/query_grid.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/stereo/config.hpp"

namespace ivoa::stereo {

enum class Verdict { kFree, kObstacle, kUnknown };

// What a footprint check measured on the way to its verdict: one value per
// ground sample the detector tests, in a fixed order for a given radius
// (NaN where it saw nothing), and the verdict they give. Introspection
// learns to predict these values as a side task (ivoa-train
// --evidence-weight): they say how close each verdict came to going the
// other way, which the verdict alone does not.
struct Evidence {
  std::vector<float> values;
  Verdict verdict = Verdict::kUnknown;
};

// Thrown by set_frame for images that do not fit the calibration; what()
// says what was received and what was expected.
class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ObstacleDetector {
 public:
  virtual ~ObstacleDetector() = default;

  virtual std::string name() const = 0;  // "jppc", "dense"

  // Raw (unrectified) pair, 8-bit BGR or gray, of the calibration's sizes.
  // Throws FrameError otherwise.
  virtual void set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) = 0;

  // Footprint check of the ground point (x, y, 0), robot frame, metres.
  virtual Verdict check(double x, double y, double radius) = 0;

  // The same check with what it measured (Evidence); empty values for a
  // detector that keeps none. JPP-C: the window cost of every ground sample
  // (obstacle iff one is >= conf_pos_thresh), all of them even after the
  // first that fails.
  virtual Evidence evidence(double x, double y, double radius) { return {{}, check(x, y, radius)}; }

  // Fills out.state for every cell of `grid` (out as made by
  // make_obstacle_grid for this grid): check() at the grid's safety radius
  // for cells in front of the camera, UNKNOWN for the others.
  virtual void evaluate(const QueryGrid& grid, obstacle_grid_t& out);
};

// "jppc" or "dense"; throws std::invalid_argument for another name or a bad
// config. Cheap: builds rectification maps, allocates nothing per frame.
std::unique_ptr<ObstacleDetector> make_detector(const std::string& name, const RigCalibration& rig,
                                                const DetectorConfig& config);
std::vector<std::string> detector_names();

int8_t to_state(Verdict verdict);  // obstacle_grid_t::STATE_*
const char* to_string(Verdict verdict);

// Shared by the detectors: checks the pair against the calibration (8-bit
// gray or BGR of the calibrated sizes), throwing FrameError; the second also
// returns both images as 8-bit gray.
void check_frame(const cv::Mat& left_raw, const cv::Mat& right_raw, const RigCalibration& rig);
void to_gray_checked(const cv::Mat& left_raw, const cv::Mat& right_raw, const RigCalibration& rig, cv::Mat& left_gray,
                     cv::Mat& right_gray);

}  // namespace ivoa::stereo
