#pragma once
// JPP-C (Ghosh & Biswas, "Joint Perception and Planning", convex world): a
// footprint is free iff every ground sample of a forward half box around it
// is a confident positive, i.e. the ground plane there matches between the
// rectified left and right images (ivoa_jpp_spec.md §1). An obstacle standing
// on the ground occludes the ground differently in the two views, so the
// ground hypothesis fails to match. Only ground points are tested.
//
// Faithful to JPP: half-resolution rectification by remapping (no
// anti-aliasing), 3-float DAISY with its index-offset quirk, 11x11 L1 window
// cost, conf_pos_thresh 0.75, forward half box dx in [0, r], dy in [-r, r]
// at step grid_size (15 samples for r = 0.10, step 0.05), texture-less
// regions matching anything. Departures, each to fix a defect of JPP's code:
//  - samples are counted with integers (JPP accumulates floats, so the
//    number of samples depended on rounding);
//  - points behind the camera are rejected (JPP projected them anyway);
//  - pixels are rounded to nearest (JPP truncates, which is wrong for
//    negative coordinates and biases by half a pixel);
//  - the CP cache is keyed on the (left, right) pixel pair (JPP: left only);
//  - the window cost divides by the pixels compared and windows mostly
//    outside give no verdict (JPP divides by 121: border bias to "match");
//  - a sample outside either image, or unobserved, makes the footprint
//    UNKNOWN rather than "not free" (JPP): the detector did not see it.
//    Any sample that fails to match still makes it OBSTACLE;
//  - the raw images are converted to gray before remapping (JPP remaps BGR,
//    then converts; both are linear, the result differs only by rounding);
//  - XR/XT are the raw left camera's pose (the project's calibration
//    convention); the rectification rotation is applied here (JPP assumed
//    them relative to the rectified camera).
#include <memory>

#include "ivoa/core/rectification.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/jpp_matcher.hpp"

namespace ivoa::stereo {

class JppcDetector : public ObstacleDetector {
 public:
  JppcDetector(const RigCalibration& rig, const JppConfig& config);

  std::string name() const override { return "jppc"; }
  void set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) override;
  Verdict check(double x, double y, double radius) override;

  // Confident positive for one robot-frame point (JPP's isFreeSpace/CP).
  PointCheck confident_positive(const Eigen::Vector3d& p_robot);

  const StereoRectification& rectification() const { return rect_; }
  const cv::Mat& left_rectified() const { return left_rect_; }
  const cv::Mat& right_rectified() const { return right_rect_; }
  JppMatcher::Stats stats() const { return matcher_.stats(); }

 private:
  RigCalibration rig_;
  JppConfig config_;
  StereoRectification rect_;
  JppMatcher matcher_;
  cv::Mat left_gray_, right_gray_, left_rect_, right_rect_;
  bool has_frame_ = false;
};

}  // namespace ivoa::stereo
