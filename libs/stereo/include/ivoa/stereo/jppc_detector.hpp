#pragma once
// JPP-C (Ghosh & Biswas, "Joint Perception and Planning", convex world): a
// footprint is free iff every ground sample in it is a confident positive,
// i.e. the ground plane there matches between the
// rectified left and right images (ivoa_jpp_spec.md §1). An obstacle standing
// on the ground occludes the ground differently in the two views, so the
// ground hypothesis fails to match. Only ground points are tested: the IVOA
// paper uses JPP-C, although JPP's shipped configs set convex_world = false;
// we follow the paper (no column checks).
//
// Faithful to JPP: half-resolution rectification by remapping (no
// anti-aliasing), 3-float DAISY with its index-offset quirk, 11x11 L1 window
// cost, conf_pos_thresh 0.75, forward half box dx in [0, r], dy in [-r, r]
// at step grid_size (15 samples for r = 0.10, step 0.05; JppConfig::footprint
// "disc" tests the samples within r instead), texture-less regions matching
// anything.
// Departures, each to fix a defect of JPP's code:
//  - samples are counted with integers (JPP accumulates floats, so the
//    number of samples depended on rounding);
//  - points behind the camera are rejected (JPP projected them anyway);
//  - pixels are rounded to nearest (JPP truncates, which is wrong for
//    negative coordinates and biases by half a pixel);
//  - the CP cache is keyed on the (left, right) pixel pair (JPP: left only);
//  - the window cost divides by the pixels compared, compares only complete
//    descriptors, and windows mostly outside give no verdict (JPP divides by
//    121 and zero-pads descriptors at the border: biased costs there);
//  - a sample outside either image, or unobserved, makes the footprint
//    UNKNOWN rather than "not free" (JPP): the detector did not see it.
//    Any sample that fails to match still makes it OBSTACLE;
//  - the raw images are converted to gray before remapping (JPP remaps BGR,
//    then converts; both are linear, the results differ by rounding only);
//  - descriptor components are cached as bytes (JPP: floats); a per-pixel
//    L1 distance moves by at most 3/510 against thresholds of 0.75 and 1.2;
//  - XR/XT are the raw left camera's pose (the project's calibration
//    convention); the rectification rotation is applied here (JPP assumed
//    them relative to the rectified camera).
//
// Work per frame is lazy, in JPP's spirit: set_frame only keeps the images;
// evaluate() rectifies and builds descriptor layers only where the grid's
// windows fall (about half the image for the default grid); a check()
// outside that region prepares the whole image. Descriptors are computed on
// first use. Not thread-safe: one detector per thread.
#include <memory>

#include "ivoa/core/rectification.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/jpp_matcher.hpp"

namespace ivoa::stereo {
class RegionRemap;

class JppcDetector : public ObstacleDetector {
 public:
  JppcDetector(const RigCalibration& rig, const JppConfig& config);
  ~JppcDetector() override;

  std::string name() const override { return "jppc"; }
  void set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) override;
  Verdict check(double x, double y, double radius) override;
  Evidence evidence(double x, double y, double radius) override;  // window costs, 15 for r = 0.10
  void evaluate(const QueryGrid& grid, obstacle_grid_t& out) override;

  // Confident positive for one robot-frame point (JPP's CP); `cost`, if
  // given, receives the window cost (NaN when unobserved).
  PointCheck confident_positive(const Eigen::Vector3d& p_robot, double* cost = nullptr);

  const StereoRectification& rectification() const { return rect_; }
  // Rectified images, valid inside the prepared regions (all of it after
  // prepare_whole_image()).
  const cv::Mat& left_rectified() const { return left_rect_; }
  const cv::Mat& right_rectified() const { return right_rect_; }
  void prepare_whole_image() { prepare({}, {}); }
  JppMatcher::Stats stats() const { return matcher_.stats(); }

 private:
  struct Projection {
    bool valid;
    cv::Point left, right;
  };
  Projection project(const Eigen::Vector3d& p_robot) const;
  // The ground samples of the footprint around (x, y) (JppConfig::footprint).
  template <class Visit>
  void for_each_sample(double x, double y, double radius, Visit visit) const;
  // Rectifies and builds descriptor layers for windows inside the regions
  // (empty: whole image).
  void prepare(cv::Rect left_region, cv::Rect right_region);

  RigCalibration rig_;
  JppConfig config_;
  StereoRectification rect_;
  JppMatcher matcher_;
  std::unique_ptr<RegionRemap> remap_left_, remap_right_;  // rect_ for regions
  cv::Mat left_raw_, right_raw_, left_rect_, right_rect_;
  bool has_frame_ = false, prepared_ = false, whole_image_ = false;
};

}  // namespace ivoa::stereo
