#include "ivoa/core/ground_warp.hpp"

#include <opencv2/imgproc.hpp>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/image_convert.hpp"

namespace ivoa {

GroundWarp::GroundWarp(const RigCalibration& rig, double far_range) {
  const RigGeometry geometry(rig);
  const CameraIntrinsics& l = rig.left;
  right_size_ = {rig.right.width, rig.right.height};
  map_x_.create(l.height, l.width, CV_32F);
  map_y_.create(l.height, l.width, CV_32F);
  const Eigen::Vector3d origin = geometry.left.origin();
  for (int v = 0; v < l.height; ++v)
    for (int u = 0; u < l.width; ++u) {
      const Eigen::Vector3d ray = geometry.left.ray({u, v});
      // Ground (z = 0) if the ray meets it within far_range, else far along the ray.
      const double t = ray.z() < 0 ? std::min(-origin.z() / ray.z(), far_range) : far_range;
      const auto pixel = geometry.right.project(origin + t * ray);
      map_x_.at<float>(v, u) = pixel ? static_cast<float>(pixel->x()) : -1.0f;
      map_y_.at<float>(v, u) = pixel ? static_cast<float>(pixel->y()) : -1.0f;
    }
}

cv::Mat GroundWarp::warp(const cv::Mat& right_bgr) const {
  CV_Assert(right_bgr.type() == CV_8UC3 && right_bgr.size() == right_size_);
  cv::Mat out;
  cv::remap(right_bgr, out, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

cv::Mat GroundWarp::stack(const cv::Mat& left_bgr, const cv::Mat& right_bgr) const {
  const auto text = [](cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); };
  if (left_bgr.type() != CV_8UC3 || right_bgr.type() != CV_8UC3 || left_bgr.size() != map_x_.size() ||
      right_bgr.size() != right_size_)
    throw ImageError("left image " + text(left_bgr.size()) + " and right " + text(right_bgr.size()) +
                     " (8-bit BGR expected), the calibration's are " + text(map_x_.size()) + " and " +
                     text(right_size_));
  cv::Mat out;
  cv::vconcat(left_bgr, warp(right_bgr), out);
  return out;
}

}  // namespace ivoa
