#include <cmath>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
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
  rig = test::make_test_rig();
  rig.stereo_T.x() = 1e308;  // was taken as a rig
  EXPECT_THROW(validate(rig, "test"), CalibrationError);
  rig = test::make_test_rig();
  rig.left_to_robot.translation().z() = -1e308;
  EXPECT_THROW(validate(rig, "test"), CalibrationError);
  rig_calibration_t msg = to_message(test::make_test_rig(), 0);
  msg.left.width = 0;
  EXPECT_THROW(from_message(msg), CalibrationError);
  msg = to_message(test::make_test_rig(), 0);  // a depth monitor took these and labelled with them
  msg.depth_min_range = 1e-9;
  EXPECT_THROW(from_message(msg), CalibrationError);
  msg = to_message(test::make_test_rig(), 0);
  msg.depth_max_range = 1e300;  // past what 16-bit millimetres can say
  EXPECT_THROW(from_message(msg), CalibrationError);
}

// A saved rig's file with `key: value` in place of that key's line (or
// added), loaded: the error, or "".
std::string load_with(const test::TempDir& dir, const std::string& key, const std::string& value) {
  save_rig_calibration(test::make_test_rig(), dir.file("rig.yml"));
  std::istringstream saved(test::read_file(dir.file("rig.yml")));
  std::string text;
  for (std::string line; std::getline(saved, line);)
    if (line.rfind(key + ":", 0) != 0) text += line + "\n";
  std::ofstream(dir.file("rig.yml")) << text << key << ": " << value << "\n";
  try {
    load_rig_calibration(dir.file("rig.yml"));
    return "";
  } catch (const CalibrationError& e) {
    return e.what();
  }
}

// A misspelt key was dropped for the default, and a range given as a string
// or a list loaded as DBL_MAX.
TEST(Calibration, MisspeltKeysAndRangesThatAreNotNumbersAreNamed) {
  test::TempDir dir;
  EXPECT_NE(load_with(dir, "depth_max_rang", "8.")
                .find("rig.yml: key 'depth_max_rang' is not a calibration key: "
                      "'depth_max_range' misspelt?"),
            std::string::npos);
  EXPECT_NE(load_with(dir, "depth_max_range", "\"8\"").find("rig.yml: key 'depth_max_range' must be a number (metres)"),
            std::string::npos);
  EXPECT_NE(load_with(dir, "depth_min_range", "[8, 9]").find("key 'depth_min_range' must be a number"),
            std::string::npos);
  EXPECT_NE(load_with(dir, "rig_name", "[1, 2]").find("key 'rig_name' must be a string"), std::string::npos);
  // A calibration tool's other keys are its business.
  EXPECT_EQ(load_with(dir, "calibration_time", "\"2026-12-06\""), "");
  EXPECT_EQ(load_with(dir, "P1", "[1, 2, 3]"), "");
}

// A lens no camera has: the simulator's renderer crashed (SIGSEGV) on
// these, and the rectification maps point outside the image.
TEST(Calibration, IntrinsicsNoLensHasAreRejected) {
  const auto refused = [](const std::function<void(CameraIntrinsics&)>& edit, const std::string& message) {
    RigCalibration rig = test::make_test_rig();
    edit(rig.right);
    try {
      validate(rig, "test");
      ADD_FAILURE() << "accepted: " << message;
    } catch (const CalibrationError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused([](CameraIntrinsics& c) { c.K(0, 0) = c.K(1, 1) = 1e-9; }, "focal lengths must be 1 to 1e6 px");
  refused([](CameraIntrinsics& c) { c.K(0, 2) = 1e300; }, "principal point (1000000");
  refused([](CameraIntrinsics& c) { c.K(1, 2) = -5; }, "must lie in the image");
  refused([](CameraIntrinsics& c) { c.D[0] = 1e6; }, "distortion coefficients must be finite and within +-100");
  // off the diagonal: a damaged matrix, not a lens (the grid's pixels went to 1e9, K[1][0] was ignored)
  refused([](CameraIntrinsics& c) { c.K(0, 1) = 1e9; }, "skew K[0][1] = 1000000000.000000 is over 0.2 of");
  refused([](CameraIntrinsics& c) { c.K(1, 0) = 1e9; }, "K[1][0] must be 0");
  RigCalibration rig = test::make_test_rig();
  rig.right.K(0, 1) = 0.01 * rig.right.K(0, 0);  // a real skew: accepted
  EXPECT_NO_THROW(validate(rig, "test"));
}

// The file's matrices as OpenCV writes them or as plain lists; anything
// else is named by file and key (OpenCV's exception used to abort the
// stereo detector).
TEST(Calibration, MatricesAsListsAreReadAndOthersNamed) {
  test::TempDir dir;
  save_rig_calibration(test::make_test_rig(), dir.file("rig.yml"));
  std::stringstream text;
  text << std::ifstream(dir.file("rig.yml")).rdbuf();
  const auto with = [&](const std::string& key, const std::string& value) {
    const std::regex block(key + ": !!opencv-matrix[\\s\\S]*?\\]");
    std::ofstream(dir.file("edited.yml")) << std::regex_replace(text.str(), block, key + ": " + value);
    return dir.file("edited.yml");
  };
  const RigCalibration listed = load_rig_calibration(with("K1", "[ 600, 0, 480, 0, 600, 300, 0, 0, 1 ]"));
  EXPECT_EQ(listed.left.K(0, 2), 480);
  EXPECT_EQ(listed.left.K(1, 1), 600);
  EXPECT_NO_THROW(load_rig_calibration(with("D1", "[ 0.01, 0, 0, 0, 0 ]")));
  const auto named = [&](const std::string& file, const std::string& message) {
    try {
      load_rig_calibration(file);
      ADD_FAILURE() << "accepted: " << message;
    } catch (const CalibrationError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(dir.file("edited.yml") + ": ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  named(with("K1", "!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 1, 2, 3, 4, 5 ]"),
        "key 'K1' is not a 3x3 matrix (an opencv-matrix or a list of numbers)");
  named(with("K1", "[ 1, 2, 3 ]"), "key 'K1' must be 3x3, it has 3 numbers");
  named(with("D1", "[ 0.1, oops, 0, 0, 0 ]"), "key 'D1' holds something that is not a number");
  std::ofstream(dir.file("edited.yml")) << std::regex_replace(text.str(), std::regex("left_width: 960"),
                                                              "left_width: abc");
  named(dir.file("edited.yml"), "keys 'left_width' and 'left_height' must be whole numbers");
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

// Calibrations come every second: the same content at another time is not
// new; another rig is; an invalid one is refused each time it comes.
TEST(CalibrationChanges, TellsANewCalibrationFromTheSameOneAgain) {
  CalibrationChanges changes;
  const RigCalibration rig = test::make_test_rig();
  ASSERT_TRUE(changes.take_if_new(to_message(rig, 1000)).has_value());
  EXPECT_FALSE(changes.take_if_new(to_message(rig, 2000)).has_value()) << "republished: not new";
  RigCalibration moved = rig;
  moved.left.K(0, 2) += 1.0;
  const auto taken = changes.take_if_new(to_message(moved, 3000));
  ASSERT_TRUE(taken.has_value());
  EXPECT_DOUBLE_EQ(taken->left.K(0, 2), moved.left.K(0, 2));
  rig_calibration_t broken = to_message(rig, 4000);
  broken.left.width = 0;
  EXPECT_THROW(changes.take_if_new(broken), CalibrationError);
  EXPECT_THROW(changes.take_if_new(broken), CalibrationError) << "not taken: checked again";
  changes.take(rig);  // from a file
  EXPECT_FALSE(changes.take_if_new(to_message(rig, 5000)).has_value());
}

}  // namespace
}  // namespace ivoa
