#pragma once
// Synthetic rectified pairs with a known disparity, for matcher tests.
#include <cstdint>

#include <opencv2/core.hpp>

namespace ivoa::test {

// Random band-limited texture (blurred uniform noise, stretched to 30..225).
cv::Mat random_texture(cv::Size size, uint64_t seed, double blur_sigma = 1.2);

// The right view of `left` for a fronto-parallel surface at `disparity`
// pixels (may be fractional): right(u, v) = left(u + disparity, v).
cv::Mat shift_to_right_view(const cv::Mat& left, double disparity);

}  // namespace ivoa::test
