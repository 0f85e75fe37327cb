#include "ivoa/core/rectification.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace ivoa {
namespace {

cv::Mat to_cv(const Eigen::MatrixXd& m) {
  cv::Mat out;
  cv::eigen2cv(m, out);
  return out;
}

}  // namespace

StereoRectification::StereoRectification(const RigCalibration& rig, double scale) {
  if (!(scale > 0.0 && scale <= 1.0)) throw CalibrationError("rectification scale must be in (0, 1]");
  const cv::Size raw(rig.left.width, rig.left.height);
  size_ = cv::Size(static_cast<int>(std::lround(raw.width * scale)), static_cast<int>(std::lround(raw.height * scale)));
  const cv::Mat K1 = to_cv(rig.left.K), K2 = to_cv(rig.right.K);
  const cv::Mat D1(1, 5, CV_64F, const_cast<double*>(rig.left.D.data()));
  const cv::Mat D2(1, 5, CV_64F, const_cast<double*>(rig.right.D.data()));
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(K1, D1, K2, D2, raw, to_cv(rig.stereo_R), to_cv(rig.stereo_T), R1, R2, P1, P2, Q,
                    cv::CALIB_ZERO_DISPARITY, 0.0, size_);
  cv::initUndistortRectifyMap(K1, D1, R1, P1, size_, CV_32FC1, map_left_x_, map_left_y_);
  cv::initUndistortRectifyMap(K2, D2, R2, P2, size_, CV_32FC1, map_right_x_, map_right_y_);

  focal_ = P1.at<double>(0, 0);
  cx_ = P1.at<double>(0, 2);
  cy_ = P1.at<double>(1, 2);
  cx_right_ = P2.at<double>(0, 2);
  baseline_ = -P2.at<double>(0, 3) / P2.at<double>(0, 0);

  // OpenCV's P1/P2 project points given in the rectified left frame
  // (R1 * left camera), so robot points go robot -> left camera -> R1.
  Eigen::Matrix3d R1e;
  cv::cv2eigen(R1, R1e);
  Eigen::Isometry3d left_to_rect = Eigen::Isometry3d::Identity();
  left_to_rect.linear() = R1e;
  rect_to_robot_ = rig.left_to_robot * left_to_rect.inverse();
  robot_to_rect_ = rect_to_robot_.inverse();
}

void StereoRectification::rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect,
                                  cv::Mat& right_rect) const {
  cv::remap(left_raw, left_rect, map_left_x_, map_left_y_, cv::INTER_LINEAR);
  cv::remap(right_raw, right_rect, map_right_x_, map_right_y_, cv::INTER_LINEAR);
}

bool StereoRectification::project(const Eigen::Vector3d& p_robot, Eigen::Vector2d& left, Eigen::Vector2d& right) const {
  const Eigen::Vector3d p = robot_to_rect_ * p_robot;
  if (p.z() < kMinProjectionDepth) return false;
  const double x = p.x() / p.z(), y = p.y() / p.z();
  left = {focal_ * x + cx_, focal_ * y + cy_};
  right = {focal_ * (x - baseline_ / p.z()) + cx_right_, left.y()};
  return true;
}

Eigen::Vector3d StereoRectification::unproject(const Eigen::Vector2d& left, double disparity) const {
  // d = (u_l - cx) - (u_r - cx_right) = f B / Z
  const double z = focal_ * baseline_ / (disparity + cx_right_ - cx_);
  const Eigen::Vector3d p((left.x() - cx_) * z / focal_, (left.y() - cy_) * z / focal_, z);
  return rect_to_robot_ * p;
}

}  // namespace ivoa
