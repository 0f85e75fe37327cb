// The driver publishes what real drivers publish, on the configured
// channels, with reproducible times; two runs of one session are identical.
#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/rig_calibration_t.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo_image_t.hpp"
#include "sim_driver.hpp"
#include "test_rig.hpp"

namespace ivoa::sim {
namespace {

using test::read_file;

constexpr int64_t kStart = 1700000000000000;

SimDriverConfig config(const std::string& log = "") {
  SimDriverConfig c;
  c.scene_file = std::string(IVOA_SIM_SCENES_DIR) + "/corridor.yaml";
  c.seed = 3;
  c.rate_hz = 10;
  c.realtime = false;
  c.frames = 3;
  c.start_utime = kStart;
  c.log_file = log;
  return c;
}

TEST(SimDriver, PublishesWhatRealDriversPublish) {
  Bus bus("memq://");
  std::vector<stereo_image_t> stereo;
  std::vector<depth_image_t> depth;
  std::vector<rig_calibration_t> rigs;
  std::vector<sim_ground_truth_t> truth;
  std::vector<std::string> order;
  bus.subscribe<stereo_image_t>("STEREO_IMAGES", [&](const stereo_image_t& m, const ReceiveInfo&) {
    stereo.push_back(m);
    order.push_back("stereo");
  });
  bus.subscribe<depth_image_t>("DEPTH_IMAGE", [&](const depth_image_t& m, const ReceiveInfo&) { depth.push_back(m); });
  bus.subscribe<rig_calibration_t>("RIG_CALIBRATION", [&](const rig_calibration_t& m, const ReceiveInfo&) {
    rigs.push_back(m);
    order.push_back("rig");
  });
  bus.subscribe<sim_ground_truth_t>("SIM_GROUND_TRUTH",
                                    [&](const sim_ground_truth_t& m, const ReceiveInfo&) { truth.push_back(m); });
  SimDriverConfig c = config();
  c.frames = 12;  // 1.2 s of session time: a second calibration message
  SimDriver driver(c, SimulatorConfig{}, bus, nullptr);
  EXPECT_EQ(driver.run(), 12);
  while (bus.handle(0) > 0) {
  }
  ASSERT_EQ(stereo.size(), 12u);
  ASSERT_EQ(depth.size(), 12u);
  ASSERT_EQ(truth.size(), 12u);
  ASSERT_EQ(rigs.size(), 2u);
  EXPECT_EQ(order.front(), "rig") << "the calibration comes first";
  EXPECT_EQ(rigs[1].utime, kStart + 1000000);
  for (size_t k = 0; k < stereo.size(); ++k) {
    EXPECT_EQ(stereo[k].seq, static_cast<int64_t>(k));
    EXPECT_EQ(stereo[k].utime, kStart + static_cast<int64_t>(k) * 100000);
    EXPECT_EQ(stereo[k].source, "simulator");
    EXPECT_EQ(depth[k].seq, static_cast<int64_t>(k));
    EXPECT_EQ(depth[k].utime, stereo[k].utime + 4000);
    EXPECT_EQ(truth[k].utime, stereo[k].utime);
    EXPECT_EQ(truth[k].seed, 3);
  }
  EXPECT_EQ(stereo[0].left.pixelformat, image_t::PIXEL_FORMAT_BAYER_RGGB);
  const cv::Mat left = decode_image(stereo[0].left);
  EXPECT_EQ(left.size(), cv::Size(960, 600));
  EXPECT_EQ(decode_depth(depth[0]).size(), cv::Size(640, 480));
  EXPECT_EQ(truth[0].surface.pixelformat, image_t::PIXEL_FORMAT_PNG);
  EXPECT_EQ(decode_image(truth[0].surface, ColorOutput::kGray).size(), cv::Size(960, 600));
  const RigCalibration rig = from_message(rigs[0]);
  EXPECT_NEAR(rig.baseline(), 0.12, 0.005);
  EXPECT_NEAR(depth[0].fx, rig.depth.K(0, 0), 1e-9);
  // The robot moves between frames.
  EXPECT_TRUE(truth[0].robot_x != truth[11].robot_x || truth[0].robot_yaw != truth[11].robot_yaw);
}

TEST(SimDriver, SessionsAreReproducible) {
  test::TempDir dir;
  for (const char* name : {"a.lcmlog", "b.lcmlog"}) {
    Bus bus("memq://");
    SimDriver driver(config(dir.file(name)), SimulatorConfig{}, bus, nullptr);
    driver.run();
  }
  const std::string a = read_file(dir.file("a.lcmlog")), b = read_file(dir.file("b.lcmlog"));
  EXPECT_GT(a.size(), 3000000u);
  EXPECT_EQ(a, b) << "same scene, seed and start time: identical logs";
}

TEST(SimDriver, ExecutableRunsAndFailsCleanly) {
  test::TempDir dir;
  const std::string driver = IVOA_SIM_DRIVER_PATH;
  const std::string common =
      " --lcm-url memq:// --as-fast-as-possible --frames 2 --start-utime 1700000000000000"
      " --log-level warn --scene " +
      std::string(IVOA_SIM_SCENES_DIR) + "/warehouse.yaml";
  ASSERT_EQ(
      std::system((driver + common + " --log " + dir.file("a.lcmlog") + " --save-rig " + dir.file("rig.yaml")).c_str()),
      0);
  ASSERT_EQ(std::system((driver + common + " --log " + dir.file("b.lcmlog")).c_str()), 0);
  EXPECT_EQ(read_file(dir.file("a.lcmlog")), read_file(dir.file("b.lcmlog")));
  EXPECT_NEAR(load_rig_calibration(dir.file("rig.yaml")).baseline(), 0.12, 0.005);
  // Events are timestamped by message utime.
  lcm::LogFile log(dir.file("a.lcmlog"), "r");
  ASSERT_TRUE(log.good());
  const lcm::LogEvent* first = log.readNextEvent();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->channel, "RIG_CALIBRATION");
  EXPECT_EQ(first->timestamp, 1700000000000000);
  // A bad scene file: exit code 3 (unusable input file).
  std::ofstream(dir.file("bad.yaml")) << "obstacles: {kinds: {dragon: 1}}\n";
  const int status =
      std::system((driver + " --lcm-url memq:// --log-level off --scene " + dir.file("bad.yaml")).c_str());
  EXPECT_EQ(WEXITSTATUS(status), 3);
  EXPECT_EQ(WEXITSTATUS(std::system((driver + " --rate -1 --log-level off 2>/dev/null").c_str())), 2);
  // A negative start time used to mean "now" without a word.
  EXPECT_EQ(WEXITSTATUS(std::system((driver + " --start-utime -5 --log-level off 2>/dev/null").c_str())), 2);
  // A rate that put frame 1 ages away hung it (or crashed it); NaN, infinite or huge values made nonsense utimes.
  for (const char* flags : {"--rate 1e-9", "--rate inf", "--rate nan", "--depth-offset-ms nan",
                            "--depth-offset-ms 1e30", "--start-utime 9223372036854775000"})
    EXPECT_EQ(WEXITSTATUS(std::system((driver + " " + flags + " --frames 1 --log-level off 2>/dev/null").c_str())), 2)
        << flags;
  // Seeds CLI11 wrapped or saturated (each ran as seed 2^64-1), and a period
  // whose microseconds overflowed into "with every frame".
  // And channels LCM refuses (it said so on stderr; the driver reported the frames published).
  const std::string too_long = "--stereo-channel " + std::string(64, 'S');
  for (const std::string& flags :
       {std::string("--seed=-1"), std::string("--seed 99999999999999999999"), std::string("--noise-seed=-2"),
        std::string("--seed 1e3"), std::string("--calibration-period 1e13"), too_long,
        std::string("--status-channel ''")})
    EXPECT_EQ(WEXITSTATUS(std::system((driver + " " + flags + " --frames 1 --log-level off 2>/dev/null").c_str())), 2)
        << flags;
}

// The scene file was replaced by a log, and a log written twice over itself
// (--log and a file:// --lcm-url) was damaged; a full disk passed as a log.
TEST(SimDriver, OutputsThatWouldLoseDataAreRefused) {
  test::TempDir dir;
  const std::string scene = dir.file("scene.yaml");
  std::ofstream(scene) << read_file(std::string(IVOA_SIM_SCENES_DIR) + "/warehouse.yaml");
  const std::string before = read_file(scene);
  const std::string driver = std::string(IVOA_SIM_DRIVER_PATH) + " --as-fast-as-possible --frames 1 --scene " + scene;
  const auto exit_code = [&](const std::string& flags) {
    return WEXITSTATUS(std::system((driver + " " + flags + " --log-level off 2>/dev/null").c_str()));
  };
  EXPECT_EQ(exit_code("--lcm-url memq:// --log " + scene), 2);
  EXPECT_EQ(exit_code("--lcm-url memq:// --save-rig " + scene), 2);
  EXPECT_EQ(exit_code("--lcm-url 'file://" + scene + "?mode=w'"), 2);
  EXPECT_EQ(read_file(scene), before) << "the scene file was written over";
  EXPECT_EQ(exit_code("--log " + dir.file("s.lcmlog") + " --lcm-url 'file://" + dir.file("s.lcmlog") + "?mode=w'"), 2);
  EXPECT_EQ(exit_code("--lcm-url memq:// --log /dev/full"), 4);
}

}  // namespace
}  // namespace ivoa::sim
