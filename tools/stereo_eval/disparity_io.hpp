#pragma once
// Ground-truth disparity maps: PFM (float), 16-bit PNG (value / divisor,
// KITTI: 256) or 8-bit PNG (Middlebury half/third-size GT such as aloeGT:
// value / divisor, 1). 0, inf and NaN mean unknown and become NaN.
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace ivoa::stereo_eval {

class DisparityFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// cv::imread that refuses, naming the file, what it cannot read and a JPEG
// cut short (which OpenCV would decode grey below the cut, with only a
// libjpeg warning that names no file).
cv::Mat read_image(const std::string& path, int imread_flags);

// CV_32F disparity in pixels of the file's resolution, NaN = unknown.
cv::Mat load_disparity(const std::string& path, double divisor = 1.0);
cv::Mat read_pfm(const std::string& path);  // raw floats, top row first
void write_pfm(const std::string& path, const cv::Mat& disparity);

// Resizes a disparity map by `scale` (nearest neighbour, so unknown stays
// unknown) and scales the disparities with it.
cv::Mat scale_disparity(const cv::Mat& disparity, double scale);

}  // namespace ivoa::stereo_eval
