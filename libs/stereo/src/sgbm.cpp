#include "ivoa/stereo/sgbm.hpp"

#include <cstdlib>
#include <limits>
#include <string>
#include <stdexcept>

namespace ivoa::stereo {
namespace {

int sgbm_mode(const std::string& mode) {
  if (mode == "3way") return cv::StereoSGBM::MODE_SGBM_3WAY;
  if (mode == "sgbm") return cv::StereoSGBM::MODE_SGBM;
  if (mode == "hh") return cv::StereoSGBM::MODE_HH;
  throw std::invalid_argument("sgbm_mode '" + mode + "': use 3way, sgbm or hh");
}

}  // namespace

SgbmMatcher::SgbmMatcher(const SgbmConfig& c) {
  const int area = c.block_size * c.block_size;
  sgbm_ = cv::StereoSGBM::create(c.min_disparity, c.num_disparities, c.block_size, c.p1 > 0 ? c.p1 : 8 * area,
                                 c.p2 > 0 ? c.p2 : 32 * area, c.disp12_max_diff, c.pre_filter_cap, c.uniqueness_ratio,
                                 c.speckle_window_size, c.speckle_range, sgbm_mode(c.mode));
}

cv::Mat SgbmMatcher::compute(const cv::Mat& left_gray, const cv::Mat& right_gray) const {
  // OpenCV aborts the process (an exception from a buffer's destructor)
  // when the disparity range is wider than the image.
  const int64_t range = std::abs(int64_t{sgbm_->getMinDisparity()}) + sgbm_->getNumDisparities();
  if (range >= left_gray.cols)
    throw std::invalid_argument("SGBM disparities " + std::to_string(sgbm_->getMinDisparity()) + " + " +
                                std::to_string(sgbm_->getNumDisparities()) + " do not fit the rectified image " +
                                std::to_string(left_gray.cols) +
                                " px wide (lower --sgbm_num_disparities or raise --sgbm_rect_scale)");
  cv::Mat fixed;  // CV_16S, disparity * 16
  sgbm_->compute(left_gray, right_gray, fixed);
  cv::Mat disparity(fixed.size(), CV_32F);
  const int invalid_below = sgbm_->getMinDisparity() * 16;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < fixed.rows; ++v) {
    const int16_t* in = fixed.ptr<int16_t>(v);
    float* out = disparity.ptr<float>(v);
    for (int u = 0; u < fixed.cols; ++u) out[u] = in[u] < invalid_below ? nan : in[u] / 16.f;
  }
  return disparity;
}

}  // namespace ivoa::stereo
