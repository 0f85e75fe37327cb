#include "ivoa/stereo/detector.hpp"

#include <opencv2/core/check.hpp>
#include <opencv2/imgproc.hpp>

#include "ivoa/stereo/dense_detector.hpp"
#include "ivoa/stereo/jppc_detector.hpp"

namespace ivoa::stereo {
namespace {

std::string describe(const cv::Mat& m) {
  if (m.empty()) return "empty";
  return std::to_string(m.cols) + "x" + std::to_string(m.rows) + " " + cv::typeToString(m.type());
}

void check_image(const cv::Mat& in, const CameraIntrinsics& camera, const std::string& side) {
  const bool ok_type = in.depth() == CV_8U && (in.channels() == 1 || in.channels() == 3);
  if (in.empty() || !ok_type || in.cols != camera.width || in.rows != camera.height)
    throw FrameError(side + " image is " + describe(in) + "; the calibration expects 8-bit gray or BGR " +
                     std::to_string(camera.width) + "x" + std::to_string(camera.height));
}

void to_gray(const cv::Mat& in, cv::Mat& out, const CameraIntrinsics& camera, const std::string& side) {
  check_image(in, camera, side);
  if (in.channels() == 3) cv::cvtColor(in, out, cv::COLOR_BGR2GRAY);
  else out = in;
}

}  // namespace

void ObstacleDetector::evaluate(const QueryGrid& grid, obstacle_grid_t& out) {
  if (out.state.size() != static_cast<size_t>(grid.size()))
    throw std::invalid_argument("evaluate: the obstacle grid has " + std::to_string(out.state.size()) +
                                " cells, the query grid " + std::to_string(grid.size()));
  const double radius = grid.config().safety_radius;
  for (int i = 0; i < grid.size(); ++i) {
    const QueryCell& cell = grid.cell(i);
    out.state[static_cast<size_t>(i)] =
        cell.projects ? to_state(check(cell.x, cell.y, radius)) : to_state(Verdict::kUnknown);
  }
}

std::unique_ptr<ObstacleDetector> make_detector(const std::string& name, const RigCalibration& rig,
                                                const DetectorConfig& config) {
  if (name == "jppc") return std::make_unique<JppcDetector>(rig, config.jpp);
  if (name == "dense") return std::make_unique<DenseDetector>(rig, config.dense);
  throw std::invalid_argument("unknown stereo detector '" + name + "' (use jppc or dense)");
}

std::vector<std::string> detector_names() { return {"jppc", "dense"}; }

int8_t to_state(Verdict verdict) {
  switch (verdict) {
    case Verdict::kFree: return obstacle_grid_t::STATE_FREE;
    case Verdict::kObstacle: return obstacle_grid_t::STATE_OBSTACLE;
    case Verdict::kUnknown: break;
  }
  return obstacle_grid_t::STATE_UNKNOWN;
}

const char* to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::kFree: return "free";
    case Verdict::kObstacle: return "obstacle";
    case Verdict::kUnknown: break;
  }
  return "unknown";
}

void check_frame(const cv::Mat& left_raw, const cv::Mat& right_raw, const RigCalibration& rig) {
  check_image(left_raw, rig.left, "left");
  check_image(right_raw, rig.right, "right");
}

void to_gray_checked(const cv::Mat& left_raw, const cv::Mat& right_raw, const RigCalibration& rig, cv::Mat& left_gray,
                     cv::Mat& right_gray) {
  to_gray(left_raw, left_gray, rig.left, "left");
  to_gray(right_raw, right_gray, rig.right, "right");
}

}  // namespace ivoa::stereo
