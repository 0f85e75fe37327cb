#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "ivoa/core/calibration.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

void expect_same(const RigCalibration& a, const RigCalibration& b) {
  EXPECT_EQ(a.rig_name, b.rig_name);
  EXPECT_EQ(a.left.width, b.left.width);
  EXPECT_EQ(a.depth.height, b.depth.height);
  EXPECT_TRUE(a.left.K.isApprox(b.left.K));
  EXPECT_TRUE(a.right.K.isApprox(b.right.K));
  EXPECT_EQ(a.left.D, b.left.D);
  EXPECT_TRUE(a.stereo_R.isApprox(b.stereo_R));
  EXPECT_TRUE(a.stereo_T.isApprox(b.stereo_T));
  EXPECT_TRUE(a.left_to_robot.isApprox(b.left_to_robot));
  EXPECT_TRUE(a.depth_to_robot.isApprox(b.depth_to_robot));
  EXPECT_DOUBLE_EQ(a.depth_max_range, b.depth_max_range);
}

TEST(Calibration, FileRoundTrip) {
  test::TempDir dir;
  const RigCalibration rig = test::make_test_rig(15.0, true);
  save_rig_calibration(rig, dir.file("rig.yml"));
  expect_same(rig, load_rig_calibration(dir.file("rig.yml")));
}

TEST(Calibration, MessageRoundTrip) {
  const RigCalibration rig = test::make_test_rig(12.0, true);
  const rig_calibration_t msg = to_message(rig, 123);
  EXPECT_EQ(msg.utime, 123);
  expect_same(rig, from_message(msg));
}

TEST(Calibration, MissingKeyIsNamed) {
  test::TempDir dir;
  std::ofstream(dir.file("bad.yml")) << "%YAML:1.0\nrig_name: x\nleft_width: 960\nleft_height: 600\n";
  try {
    load_rig_calibration(dir.file("bad.yml"));
    FAIL() << "expected CalibrationError";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("K1"), std::string::npos) << e.what();
  }
}

TEST(Calibration, FileThatIsNotYamlIsNamedOnOneLine) {
  test::TempDir dir;
  std::ofstream(dir.file("garbage.yml")) << "garbage: [\n";
  try {
    load_rig_calibration(dir.file("garbage.yml"));
    FAIL() << "expected CalibrationError";
  } catch (const CalibrationError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(dir.file("garbage.yml") + ": not a readable OpenCV YAML file (", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(Calibration, MissingFileIsNamed) {
  try {
    load_rig_calibration("/nonexistent/rig.yml");
    FAIL() << "expected CalibrationError";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rig.yml"), std::string::npos) << e.what();
  }
}

TEST(Calibration, InvalidValuesAreRejected) {
  RigCalibration rig = test::make_test_rig();
  rig.left.K(0, 0) = -1;
  EXPECT_THROW(validate(rig, "test"), CalibrationError);
  rig = test::make_test_rig();
  rig.stereo_R(0, 0) = 2;  // not a rotation
  EXPECT_THROW(validate(rig, "test"), CalibrationError);
  rig = test::make_test_rig();
  rig.depth_max_range = 0.1;
  EXPECT_THROW(validate(rig, "test"), CalibrationError);
  rig_calibration_t msg = to_message(test::make_test_rig(), 0);
  msg.left.width = 0;
  EXPECT_THROW(from_message(msg), CalibrationError);
}

// Such a camera would pass every other check, then hold a detector busy for
// seconds building maps that do not fit in memory, and OpenCV would refuse it.
TEST(Calibration, ImagesTooLargeForOpenCVsRemapAreRejected) {
  rig_calibration_t msg = to_message(test::make_test_rig(), 0);
  msg.right.width = 60000;
  try {
    from_message(msg);
    FAIL() << "accepted a 60000 px wide right camera";
  } catch (const CalibrationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("right camera image size 60000x600"), std::string::npos) << what;
    EXPECT_NE(what.find("is not under 32767 px a side"), std::string::npos) << what;
  }
  msg.right.width = 32766;
  EXPECT_NO_THROW(from_message(msg));
  // under remap's limit a side, but 1.07 Gpx: the monitor needed 1.75 GB
  msg.right.height = 32766;
  try {
    from_message(msg);
    FAIL() << "accepted a 32766x32766 right camera";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("32766x32766 is over 67108864 pixels"), std::string::npos) << e.what();
  }
}

TEST(Calibration, OpticalAxesMapToTheRobotFrame) {
  const Eigen::Matrix3d level = optical_to_robot(0.0);
  EXPECT_TRUE((level * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));   // forward
  EXPECT_TRUE((level * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY()));  // right
  EXPECT_TRUE((level * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));  // down
  // Pitched 30 degrees down, the optical axis points at the ground ahead.
  const Eigen::Vector3d axis = optical_to_robot(M_PI / 6) * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(axis.x(), std::cos(M_PI / 6), 1e-12);
  EXPECT_NEAR(axis.y(), 0.0, 1e-12);
  EXPECT_NEAR(axis.z(), -0.5, 1e-12);
}

}  // namespace
}  // namespace ivoa
