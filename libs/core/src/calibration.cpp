#include "ivoa/core/calibration.hpp"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/rig_calibration_t.hpp"

namespace ivoa {
namespace {

constexpr double kMaxDistortion = 100;  // plumb-bob k1..k3, p1, p2: real lenses stay within a few units
constexpr double kMaxSkew = 0.2;        // |K[0][1]| / fx: see validate_camera

void check(bool ok, const std::string& where, const std::string& what) {
  if (!ok) throw CalibrationError(where + ": " + what);
}

void validate_rotation(const Eigen::Matrix3d& R, const std::string& where, const std::string& key) {
  const double orthogonality = (R * R.transpose() - Eigen::Matrix3d::Identity()).norm();
  check(R.allFinite() && orthogonality < 1e-3 && std::abs(R.determinant() - 1.0) < 1e-3, where,
        key + " is not a rotation matrix (orthogonality error " + std::to_string(orthogonality) + ")");
}

void validate_camera(const CameraIntrinsics& cam, const std::string& where, const std::string& key) {
  check(cam.width > 0 && cam.height > 0, where,
        key + " image size must be positive, got " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  // cv::remap, which rectifies and warps every image, takes images under SHRT_MAX a side
  check(cam.width < SHRT_MAX && cam.height < SHRT_MAX, where,
        key + " image size " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + " is not under " +
            std::to_string(SHRT_MAX) + " px a side (OpenCV's remap)");
  // every process sizes its rectification maps and grids from it
  check(static_cast<int64_t>(cam.width) * cam.height <= kMaxImagePixels, where,
        key + " image size " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + " is over " +
            std::to_string(kMaxImagePixels) + " pixels");
  check(cam.K.allFinite() && cam.K(0, 0) > 0 && cam.K(1, 1) > 0, where,
        key + " focal lengths must be positive and finite");
  check(cam.K(2, 0) == 0 && cam.K(2, 1) == 0 && cam.K(2, 2) == 1, where, key + " last row must be [0 0 1]");
  check(cam.K(1, 0) == 0, where, key + " K[1][0] must be 0 (a camera matrix is upper triangular)");
  // Skew is fx / tan of the angle between the pixel axes: 0.2 fx is 11 degrees
  // off square, far past any sensor; larger values are damage.
  check(std::abs(cam.K(0, 1)) <= kMaxSkew * cam.K(0, 0), where,
        key + " skew K[0][1] = " + std::to_string(cam.K(0, 1)) + " is over 0.2 of the focal length fx");
  // Past these no lens is described, and the simulator's rays and the
  // rectification maps leave the image (the renderer crashed on them).
  check(cam.K(0, 0) >= kMinFocalPx && cam.K(1, 1) >= kMinFocalPx && cam.K(0, 0) <= kMaxFocalPx &&
            cam.K(1, 1) <= kMaxFocalPx,
        where, key + " focal lengths must be 1 to 1e6 px");
  check(cam.K(0, 2) >= 0 && cam.K(0, 2) <= cam.width && cam.K(1, 2) >= 0 && cam.K(1, 2) <= cam.height, where,
        key + " principal point (" + std::to_string(cam.K(0, 2)) + ", " + std::to_string(cam.K(1, 2)) +
            ") must lie in the image");
  for (double d : cam.D)
    check(std::isfinite(d) && std::abs(d) <= kMaxDistortion, where,
          key + " distortion coefficients must be finite and within +-" +
              std::to_string(static_cast<int>(kMaxDistortion)));
}

// A key's numbers, as one column: an opencv-matrix or a plain YAML list
// (JPP writes T as one). Anything else names the key instead of letting
// OpenCV's exception end the process.
cv::Mat read_numbers(const cv::FileStorage& fs, const std::string& key, const std::string& path,
                     const std::string& what) {
  const cv::FileNode node = fs[key];
  check(!node.empty(), path, "missing key '" + key + "' (" + what + ")");
  cv::Mat m;
  try {
    if (node.isSeq()) {
      std::vector<double> v;
      for (const cv::FileNode& item : node) {
        check(item.isReal() || item.isInt(), path, "key '" + key + "' holds something that is not a number");
        v.push_back(static_cast<double>(item));
      }
      m = cv::Mat(v, true);
    } else {
      node >> m;
    }
  } catch (const cv::Exception&) {
    m.release();
  }
  check(!m.empty(), path, "key '" + key + "' is not a " + what + " (an opencv-matrix or a list of numbers)");
  m.convertTo(m, CV_64F);
  return m.reshape(1, static_cast<int>(m.total()));
}

Eigen::Matrix3d read_matrix3(const cv::FileStorage& fs, const std::string& key, const std::string& path) {
  const cv::Mat m = read_numbers(fs, key, path, "3x3 matrix");
  check(m.total() == 9, path, "key '" + key + "' must be 3x3, it has " + std::to_string(m.total()) + " numbers");
  Eigen::Matrix3d out;
  cv::cv2eigen(m.reshape(1, 3), out);  // row by row
  return out;
}

Eigen::Vector3d read_vector3(const cv::FileStorage& fs, const std::string& key, const std::string& path) {
  const cv::Mat m = read_numbers(fs, key, path, "3-vector");
  check(m.total() == 3, path, "key '" + key + "' must have 3 elements");
  return {m.at<double>(0), m.at<double>(1), m.at<double>(2)};
}

CameraIntrinsics read_camera(const cv::FileStorage& fs, const std::string& name, const std::string& K_key,
                             const std::string& D_key, const std::string& path) {
  CameraIntrinsics cam;
  cam.name = name;
  const cv::FileNode w = fs[name + "_width"], h = fs[name + "_height"];
  check(!w.empty() && !h.empty(), path, "missing key '" + name + "_width' or '" + name + "_height'");
  check(w.isInt() && h.isInt(), path, "keys '" + name + "_width' and '" + name + "_height' must be whole numbers");
  cam.width = static_cast<int>(w);
  cam.height = static_cast<int>(h);
  cam.K = read_matrix3(fs, K_key, path);
  const cv::Mat D = read_numbers(fs, D_key, path, "1x5 distortion");
  check(D.total() == 5 || D.total() == 4, path, "key '" + D_key + "' must have 4 or 5 elements");
  for (size_t i = 0; i < D.total(); ++i) cam.D[i] = D.at<double>(static_cast<int>(i));
  return cam;
}

// An optional number in metres: a string or a list there loaded as DBL_MAX.
void read_range(const cv::FileStorage& fs, const std::string& key, const std::string& path, double& value) {
  const cv::FileNode node = fs[key];
  if (node.empty()) return;
  check(node.isReal() || node.isInt(), path, "key '" + key + "' must be a number (metres)");
  value = static_cast<double>(node);
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t substitute = diagonal + (a[i - 1] != b[j - 1]);
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitute});
    }
  }
  return row[b.size()];
}

// Other keys (a calibration tool's metadata, R1/P1/Q) are left alone, but
// one a letter or two from a key of ours is a misspelling whose value
// would be dropped for the default (depth_max_rang: 8 ran at 4.5 m).
void refuse_misspelt_keys(const cv::FileStorage& fs, const std::string& path) {
  static const std::vector<std::string> known = {"rig_name",
                                                 "left_width",
                                                 "left_height",
                                                 "K1",
                                                 "D1",
                                                 "right_width",
                                                 "right_height",
                                                 "K2",
                                                 "D2",
                                                 "R",
                                                 "T",
                                                 "XR",
                                                 "XT",
                                                 "depth_width",
                                                 "depth_height",
                                                 "K_depth",
                                                 "D_depth",
                                                 "XR_depth",
                                                 "XT_depth",
                                                 "depth_min_range",
                                                 "depth_max_range"};
  for (const cv::FileNode& node : fs.root()) {
    const std::string key = node.name();
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    for (const std::string& k : known)
      check(k.size() < 4 || edit_distance(key, k) > 2, path,
            "key '" + key + "' is not a calibration key: '" + k + "' misspelt?");
  }
}

Eigen::Isometry3d make_isometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& T) {
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = R;
  iso.translation() = T;
  return iso;
}

void write_camera(cv::FileStorage& fs, const CameraIntrinsics& cam, const std::string& K_key,
                  const std::string& D_key) {
  fs << cam.name + "_width" << cam.width << cam.name + "_height" << cam.height;
  cv::Mat K;
  cv::eigen2cv(cam.K, K);
  fs << K_key << K << D_key << cv::Mat(1, 5, CV_64F, const_cast<double*>(cam.D.data()));
}

void write_transform(cv::FileStorage& fs, const Eigen::Isometry3d& iso, const std::string& R_key,
                     const std::string& T_key) {
  cv::Mat R, T;
  cv::eigen2cv(Eigen::Matrix3d(iso.linear()), R);
  cv::eigen2cv(Eigen::Vector3d(iso.translation()), T);
  fs << R_key << R << T_key << T;
}

template <size_t N>
void copy_out(const Eigen::MatrixXd& m, double (&dst)[N]) {  // row-major
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) dst[r * m.cols() + c] = m(r, c);
}

Eigen::Matrix3d matrix_in(const double (&src)[9]) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(src);
}

camera_intrinsics_t camera_to_message(const CameraIntrinsics& cam, int64_t utime) {
  camera_intrinsics_t msg;
  msg.utime = utime;
  msg.name = cam.name;
  msg.width = cam.width;
  msg.height = cam.height;
  copy_out(cam.K, msg.K);
  for (size_t i = 0; i < 5; ++i) msg.D[i] = cam.D[i];
  return msg;
}

CameraIntrinsics camera_from_message(const camera_intrinsics_t& msg) {
  CameraIntrinsics cam;
  cam.name = msg.name;
  cam.width = msg.width;
  cam.height = msg.height;
  cam.K = matrix_in(msg.K);
  for (size_t i = 0; i < 5; ++i) cam.D[i] = msg.D[i];
  return cam;
}

}  // namespace

Eigen::Matrix3d optical_to_robot(double pitch_down_rad) {
  // Optical x right, y down, z forward -> robot x forward, y left, z up.
  Eigen::Matrix3d axes;
  axes << 0, 0, 1,  //
      -1, 0, 0,     //
      0, -1, 0;
  return Eigen::AngleAxisd(pitch_down_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * axes;
}

void validate(const RigCalibration& rig, const std::string& where) {
  validate_camera(rig.left, where, "left camera");
  validate_camera(rig.right, where, "right camera");
  validate_camera(rig.depth, where, "depth sensor");
  validate_rotation(rig.stereo_R, where, "stereo R");
  // Bounded as the lenses are: a baseline of 1e308 m was taken as a rig.
  check(rig.stereo_T.allFinite() && rig.baseline() > 1e-3 && rig.baseline() <= kMaxBaselineM, where,
        "stereo T must be a baseline of 1 mm to 10 m");
  validate_rotation(rig.left_to_robot.linear(), where, "left camera -> robot rotation");
  validate_rotation(rig.depth_to_robot.linear(), where, "depth sensor -> robot rotation");
  const auto on_robot = [](const Eigen::Isometry3d& t) {
    return t.translation().allFinite() && t.translation().norm() <= kMaxMountM;
  };
  check(on_robot(rig.left_to_robot) && on_robot(rig.depth_to_robot), where,
        "camera -> robot translations must be finite and within 100 m of the robot");
  // Depth images are millimetres in 16 bits: 65.535 m is the farthest reading.
  check(rig.depth_min_range >= 1e-3 && rig.depth_max_range > rig.depth_min_range && rig.depth_max_range <= 65.535,
        where, "depth range must satisfy 1 mm <= min < max <= 65.535 m (16-bit millimetres)");
}

RigCalibration load_rig_calibration(const std::string& path) {
  // said here, where OpenCV would log its own error line before ours
  if (const std::string why = why_not_a_file(path); !why.empty())
    throw CalibrationError(path + ": cannot read the calibration file: " + why);
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    std::string why = e.msg;  // OpenCV ends it with a newline: one log line instead
    while (!why.empty() && std::isspace(static_cast<unsigned char>(why.back()))) why.pop_back();
    throw CalibrationError(path + ": not a readable OpenCV YAML file (" + why + ")");
  }
  check(fs.isOpened(), path, "cannot open calibration file");
  refuse_misspelt_keys(fs, path);
  RigCalibration rig;
  const cv::FileNode name = fs["rig_name"];
  check(name.empty() || name.isString(), path, "key 'rig_name' must be a string");
  if (!name.empty()) name >> rig.rig_name;
  rig.left = read_camera(fs, "left", "K1", "D1", path);
  rig.right = read_camera(fs, "right", "K2", "D2", path);
  rig.stereo_R = read_matrix3(fs, "R", path);
  rig.stereo_T = read_vector3(fs, "T", path);
  rig.left_to_robot = make_isometry(read_matrix3(fs, "XR", path), read_vector3(fs, "XT", path));
  rig.depth = read_camera(fs, "depth", "K_depth", "D_depth", path);
  rig.depth_to_robot = make_isometry(read_matrix3(fs, "XR_depth", path), read_vector3(fs, "XT_depth", path));
  read_range(fs, "depth_min_range", path, rig.depth_min_range);
  read_range(fs, "depth_max_range", path, rig.depth_max_range);
  validate(rig, path);
  return rig;
}

void save_rig_calibration(const RigCalibration& rig, const std::string& path) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  check(fs.isOpened(), path, "cannot open calibration file for writing");
  fs.writeComment(
      "IVOA rig calibration. Robot frame: x forward, y left, z up, ground z = 0, metres.\n"
      "Camera frames are optical (x right, y down, z forward) for the raw images.\n"
      "K1/D1 left, K2/D2 right, R/T left -> right (p_right = R p_left + T),\n"
      "XR/XT left camera -> robot (p_robot = XR p_left + XT), *_depth for the depth sensor.");
  fs << "rig_name" << rig.rig_name;
  write_camera(fs, rig.left, "K1", "D1");
  write_camera(fs, rig.right, "K2", "D2");
  cv::Mat R, T;
  cv::eigen2cv(rig.stereo_R, R);
  cv::eigen2cv(rig.stereo_T, T);
  fs << "R" << R << "T" << T;
  write_transform(fs, rig.left_to_robot, "XR", "XT");
  write_camera(fs, rig.depth, "K_depth", "D_depth");
  write_transform(fs, rig.depth_to_robot, "XR_depth", "XT_depth");
  fs << "depth_min_range" << rig.depth_min_range << "depth_max_range" << rig.depth_max_range;
}

namespace {

// The message's bytes without its publication time.
std::vector<uint8_t> calibration_content(rig_calibration_t msg) {
  msg.utime = 0;
  set_counts(msg);
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace

std::optional<RigCalibration> CalibrationChanges::take_if_new(const rig_calibration_t& msg) {
  std::vector<uint8_t> content = calibration_content(msg);
  if (content == content_) return std::nullopt;
  RigCalibration rig = from_message(msg);
  content_ = std::move(content);
  return rig;
}

void CalibrationChanges::take(const RigCalibration& rig) { content_ = calibration_content(to_message(rig, 0)); }

rig_calibration_t to_message(const RigCalibration& rig, int64_t utime) {
  rig_calibration_t msg;
  msg.utime = utime;
  msg.rig_name = rig.rig_name;
  msg.left = camera_to_message(rig.left, 0);
  msg.right = camera_to_message(rig.right, 0);
  copy_out(rig.stereo_R, msg.stereo_R);
  copy_out(rig.stereo_T, msg.stereo_T);
  copy_out(Eigen::Matrix3d(rig.left_to_robot.linear()), msg.left_to_robot_R);
  copy_out(Eigen::Vector3d(rig.left_to_robot.translation()), msg.left_to_robot_T);
  msg.depth = camera_to_message(rig.depth, 0);
  copy_out(Eigen::Matrix3d(rig.depth_to_robot.linear()), msg.depth_to_robot_R);
  copy_out(Eigen::Vector3d(rig.depth_to_robot.translation()), msg.depth_to_robot_T);
  msg.depth_min_range = rig.depth_min_range;
  msg.depth_max_range = rig.depth_max_range;
  return msg;
}

RigCalibration from_message(const rig_calibration_t& msg) {
  RigCalibration rig;
  rig.rig_name = msg.rig_name;
  rig.left = camera_from_message(msg.left);
  rig.right = camera_from_message(msg.right);
  rig.stereo_R = matrix_in(msg.stereo_R);
  rig.stereo_T = {msg.stereo_T[0], msg.stereo_T[1], msg.stereo_T[2]};
  rig.left_to_robot = make_isometry(matrix_in(msg.left_to_robot_R),
                                    {msg.left_to_robot_T[0], msg.left_to_robot_T[1], msg.left_to_robot_T[2]});
  rig.depth = camera_from_message(msg.depth);
  rig.depth_to_robot = make_isometry(matrix_in(msg.depth_to_robot_R),
                                     {msg.depth_to_robot_T[0], msg.depth_to_robot_T[1], msg.depth_to_robot_T[2]});
  rig.depth_min_range = msg.depth_min_range;
  rig.depth_max_range = msg.depth_max_range;
  validate(rig, "rig_calibration_t message '" + msg.rig_name + "'");
  return rig;
}

}  // namespace ivoa
