#pragma once
// Stereo rectification (OpenCV stereoRectify, zero-disparity, alpha 0) at an
// optional output scale, and projection of robot points into the rectified
// pair. Perception models that search along rows work in this space.
#include <opencv2/core.hpp>
#include <Eigen/Core>

#include "ivoa/core/calibration.hpp"
#include "ivoa/core/camera_model.hpp"

namespace ivoa {

class StereoRectification {
 public:
  // scale < 1 shrinks the rectified images (JPP runs at half resolution).
  StereoRectification(const RigCalibration& rig, double scale = 1.0);

  // Remaps raw (distorted) images into the rectified pair (bilinear).
  void rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect, cv::Mat& right_rect) const;

  // Robot point -> rectified left and right pixels; false if behind the camera.
  bool project(const Eigen::Vector3d& p_robot, Eigen::Vector2d& left, Eigen::Vector2d& right) const;
  // Rectified left pixel and disparity -> robot point.
  Eigen::Vector3d unproject(const Eigen::Vector2d& left, double disparity) const;
  // Robot point -> rectified left camera frame (x right, y down, z forward).
  Eigen::Vector3d to_rectified_camera(const Eigen::Vector3d& p_robot) const { return robot_to_rect_ * p_robot; }
  const Eigen::Isometry3d& rectified_camera_to_robot() const { return rect_to_robot_; }

  cv::Size size() const { return size_; }
  double focal() const { return focal_; }        // rectified focal length, pixels
  double baseline() const { return baseline_; }  // metres
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  double cx_right() const { return cx_right_; }

 private:
  cv::Size size_;
  double focal_ = 0, baseline_ = 0, cx_ = 0, cy_ = 0, cx_right_ = 0;
  Eigen::Isometry3d robot_to_rect_;
  Eigen::Isometry3d rect_to_robot_;
  cv::Mat map_left_x_, map_left_y_, map_right_x_, map_right_y_;
};

}  // namespace ivoa
