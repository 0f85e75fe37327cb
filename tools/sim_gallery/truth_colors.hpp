#pragma once
// False-colour pictures of simulator outputs, for people to look at.
#include <opencv2/core.hpp>

namespace ivoa::sim {

// Depth in millimetres -> colour (near red, far blue), invalid black.
cv::Mat colorize_depth(const cv::Mat& depth_mm, double max_mm = 5000);
// Surface classes in flat colours, phenomena as tints and stripes on top.
cv::Mat colorize_truth(const cv::Mat& surface, const cv::Mat& phenomena);
// A strip explaining colorize_truth's colours, `width` pixels wide.
cv::Mat truth_legend(int width);

}  // namespace ivoa::sim
