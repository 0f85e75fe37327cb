#pragma once
// The dense stereo detector: SGBM disparity on the rectified pair, every
// valid pixel unprojected to a robot-frame point, points binned on the
// ground plane. A footprint (a horizontal disc of radius r) is
//  - OBSTACLE if enough of its points stand above the ground (z in
//    [min_obstacle_height, max_obstacle_height]) or enough lie clearly below
//    it (z < -hole_depth: what stereo sees in reflections, wet floors and
//    holes); enough = min_obstacle_points and min_obstacle_fraction of the
//    disc's valid points;
//  - FREE if it holds >= min_ground_points ground points and no obstacle;
//  - UNKNOWN otherwise (too few valid points, e.g. no disparity there).
#include <vector>

#include "ivoa/core/rectification.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/sgbm.hpp"

namespace ivoa::stereo {

class DenseDetector : public ObstacleDetector {
 public:
  DenseDetector(const RigCalibration& rig, const DenseConfig& config);

  std::string name() const override { return "dense"; }
  void set_frame(const cv::Mat& left_raw, const cv::Mat& right_raw) override;
  Verdict check(double x, double y, double radius) override;

  struct Counts {
    int ground = 0, above = 0, below = 0;
  };
  Counts count_points(double x, double y, double radius) const;

  const StereoRectification& rectification() const { return rect_; }
  const cv::Mat& disparity() const { return disparity_; }  // CV_32F, NaN = none
  const cv::Mat& left_rectified() const { return left_rect_; }

 private:
  struct Point {
    float x, y, z;
  };
  void build_point_bins();
  int bin_of(double x, double y) const;

  RigCalibration rig_;
  DenseConfig config_;
  StereoRectification rect_;
  SgbmMatcher sgbm_;
  cv::Mat left_gray_, right_gray_, left_rect_, right_rect_, disparity_;
  // Points sorted by ground bin (compressed rows: bin b holds
  // points_[bin_start_[b] .. bin_start_[b + 1])).
  int bins_per_side_ = 0;
  std::vector<Point> points_;
  std::vector<int> bin_start_;
};

}  // namespace ivoa::stereo
