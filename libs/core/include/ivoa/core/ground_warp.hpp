#pragma once
// The right image as the left camera would see it if the world were the
// flat ground: every left pixel takes the right image's colour where the
// ground point under it (or, looking above the horizon, a point far along
// its ray) projects. On free ground the warped right view matches the left
// one; on anything standing up, reflected in the floor or matched wrongly,
// it does not, which is what a stereo detector's ground check looks at.
// The introspection model's second view (ModelInfo::views = 2).
#include <opencv2/core.hpp>

#include "ivoa/core/calibration.hpp"

namespace ivoa {

class GroundWarp {
 public:
  // far_range: metres along the ray used for pixels that never meet the
  // ground (or meet it beyond this).
  explicit GroundWarp(const RigCalibration& rig, double far_range = 30.0);
  // Raw right image (8-bit BGR) -> image of the left's size; pixels whose
  // ground point the right camera does not see are black.
  cv::Mat warp(const cv::Mat& right_bgr) const;
  // A two-view model's input: the left image with the warped right one
  // stacked below it (2 x height rows). ImageError, naming the sizes, for
  // images of other sizes than the calibration's.
  cv::Mat stack(const cv::Mat& left_bgr, const cv::Mat& right_bgr) const;
  // Where the right image is sampled for left pixel (u, v).
  cv::Point2f source(int u, int v) const { return {map_x_.at<float>(v, u), map_y_.at<float>(v, u)}; }

 private:
  cv::Size right_size_;
  cv::Mat map_x_, map_y_;  // CV_32F, left image size
};

}  // namespace ivoa
