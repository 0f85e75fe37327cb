#pragma once
// Dense disparity with OpenCV's semi-global block matching.
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "ivoa/stereo/config.hpp"

namespace ivoa::stereo {

class SgbmMatcher {
 public:
  explicit SgbmMatcher(const SgbmConfig& config);
  // Rectified 8-bit gray pair -> CV_32F disparity in pixels (left image),
  // NaN where SGBM gives none (occluded, not unique, speckle, no texture).
  cv::Mat compute(const cv::Mat& left_gray, const cv::Mat& right_gray) const;

 private:
  cv::Ptr<cv::StereoSGBM> sgbm_;
};

}  // namespace ivoa::stereo
