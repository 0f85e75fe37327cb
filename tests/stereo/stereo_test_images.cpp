#include "stereo_test_images.hpp"

#include <opencv2/imgproc.hpp>

namespace ivoa::test {

cv::Mat random_texture(cv::Size size, uint64_t seed, double blur_sigma) {
  cv::Mat noise(size, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), blur_sigma);
  cv::normalize(noise, noise, 30, 225, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U);
  return out;
}

cv::Mat shift_to_right_view(const cv::Mat& left, double disparity) {
  cv::Mat map_x(left.size(), CV_32F), map_y(left.size(), CV_32F);
  for (int v = 0; v < left.rows; ++v) {
    for (int u = 0; u < left.cols; ++u) {
      map_x.at<float>(v, u) = static_cast<float>(u + disparity);
      map_y.at<float>(v, u) = static_cast<float>(v);
    }
  }
  cv::Mat right;
  cv::remap(left, right, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return right;
}

}  // namespace ivoa::test
