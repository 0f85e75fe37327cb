#pragma once
// Helpers shared by the simulator tests: rectification with true
// disparities, SGBM, and small scene builders.
#include <opencv2/core.hpp>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/rectification.hpp"
#include "ivoa/sim/simulator.hpp"

namespace ivoa::sim::test {

// A rectified pair with the true disparity of every rectified left pixel
// the ground truth covers (NaN elsewhere), from truth_depth through core's
// camera model and rectification.
struct RectifiedPair {
  cv::Mat left, right;     // CV_8UC1
  cv::Mat true_disparity;  // CV_32FC1
  cv::Mat true_surface;    // CV_8UC1 (255 where unknown)
  cv::Mat true_phenomena;  // CV_8UC1
};
RectifiedPair rectify_with_truth(const SimFrame& frame, const RigCalibration& rig, const StereoRectification& rect);

// OpenCV SGBM disparity in pixels (NaN where invalid).
cv::Mat sgbm_disparity(const cv::Mat& left_gray, const cv::Mat& right_gray, int num_disparities = 96);

// Ground-plane disparity at a rectified left pixel (NaN above the horizon).
double ground_disparity(const StereoRectification& rect, double u, double v);

}  // namespace ivoa::sim::test
