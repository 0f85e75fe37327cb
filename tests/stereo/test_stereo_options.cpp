// Detector parameters from flags and from a --config file, by JPP's names.
#include <fstream>
#include <set>
#include <string>

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/stereo/config.hpp"
#include "ivoa/stereo/options.hpp"
#include "test_rig.hpp"

namespace ivoa::stereo {
namespace {

struct Parsed {
  int code;
  DetectorConfig detector;
  QueryGridConfig grid;
};

Parsed parse(std::vector<std::string> args) {
  CLI::App app;
  CommonOptions common;
  Parsed out{};
  add_common_options(app, common);
  add_detector_options(app, out.detector);
  add_query_grid_options(app, out.grid);
  std::vector<char*> argv{const_cast<char*>("test")};
  for (auto& a : args) argv.push_back(a.data());
  out.code = parse_command_line(app, static_cast<int>(argv.size()), argv.data());
  return out;
}

TEST(StereoOptions, FlagsUseJppNames) {
  const Parsed p = parse({"--conf_pos_thresh", "0.5", "--SAD_window_size", "3", "--daisy_R", "7.5", "--grid_size",
                          "0.025", "--sgbm_num_disparities", "128", "--dense_min_ground_points", "20"});
  ASSERT_EQ(p.code, -1);
  EXPECT_EQ(p.detector.jpp.conf_pos_thresh, 0.5);
  EXPECT_EQ(p.detector.jpp.SAD_window_size, 3);
  EXPECT_EQ(p.detector.jpp.daisy_R, 7.5);
  EXPECT_EQ(p.detector.jpp.grid_size, 0.025);
  EXPECT_EQ(p.detector.dense.sgbm.num_disparities, 128);
  EXPECT_EQ(p.detector.dense.min_ground_points, 20);
  EXPECT_EQ(parse({"--sgbm_mode", "fast"}).code, kExitUsage);
  // What OpenCV's StereoSGBM would refuse at every frame is refused at the start.
  EXPECT_EQ(parse({"--sgbm_block_size", "4"}).code, kExitUsage);
  EXPECT_EQ(parse({"--sgbm_num_disparities", "17"}).code, kExitUsage);
  EXPECT_EQ(parse({"--sgbm_num_disparities", "0"}).code, kExitUsage);
  EXPECT_EQ(parse({"--sgbm_block_size", "7", "--sgbm_num_disparities", "64"}).code, -1);
}

TEST(StereoOptions, QueryGridThatCannotBeBuiltIsAUsageError) {
  EXPECT_EQ(parse({"--grid-spacing", "0"}).code, kExitUsage);
  EXPECT_EQ(parse({"--safety-radius", "-0.1"}).code, kExitUsage);
  EXPECT_EQ(parse({"--grid-x-min", "3", "--grid-x-max", "1"}).code, kExitUsage);
  EXPECT_EQ(parse({"--grid-y-max", "-2"}).code, kExitUsage);
  // Grids no robot needs that would fill memory (a patch per cell per frame in a dataset).
  EXPECT_EQ(parse({"--grid-spacing", "0.001"}).code, kExitUsage);
  EXPECT_EQ(parse({"--grid-x-max", "1000"}).code, kExitUsage);
  EXPECT_EQ(parse({"--safety-radius", "50"}).code, kExitUsage);
  EXPECT_EQ(parse({"--grid-spacing", "0.03"}).code, -1) << "84 x 101 cells: allowed";
  const Parsed one_row = parse({"--grid-x-min", "1", "--grid-x-max", "1"});
  ASSERT_EQ(one_row.code, -1);
  EXPECT_EQ(one_row.grid.x_min, 1.0);
}

TEST(StereoOptions, ConfigFileSetsThemByName) {
  test::TempDir dir;
  std::ofstream(dir.file("jpp.ini")) << "conf_pos_thresh = 0.6\ndaisy_Q = 3\nsgbm_mode = sgbm\ngrid-x-max = 2.0\n";
  const Parsed p = parse({"--config", dir.file("jpp.ini")});
  ASSERT_EQ(p.code, -1);
  EXPECT_EQ(p.detector.jpp.conf_pos_thresh, 0.6);
  EXPECT_EQ(p.detector.jpp.daisy_Q, 3);
  EXPECT_EQ(p.detector.dense.sgbm.mode, "sgbm");
  EXPECT_EQ(p.grid.x_max, 2.0);
}

TEST(StereoOptions, ConfigKeyThatNamesNoFlagIsRefused) {
  // A misspelt key used to be dropped silently, leaving the default in force.
  test::TempDir dir;
  std::ofstream(dir.file("typo.ini")) << "conf_pos_thres = 0.6\n";
  EXPECT_EQ(parse({"--config", dir.file("typo.ini")}).code, kExitUsage);
}

TEST(StereoOptions, ShippedExampleConfigHoldsTheDefaults) {
  // processes/stereo_detector/stereo_detector.ini documents every default.
  CLI::App app;
  CommonOptions common;
  DetectorConfig detector;
  QueryGridConfig grid;
  add_common_options(app, common);
  add_detector_options(app, detector);
  add_query_grid_options(app, grid);
  std::string config = IVOA_STEREO_EXAMPLE_CONFIG;
  std::vector<char*> argv{const_cast<char*>("test"), const_cast<char*>("--config"), config.data()};
  ASSERT_EQ(parse_command_line(app, 3, argv.data()), -1);
  const JppConfig jpp_defaults;
  const DenseConfig dense_defaults;
  EXPECT_EQ(detector.jpp.conf_pos_thresh, jpp_defaults.conf_pos_thresh);
  EXPECT_EQ(detector.jpp.grid_size, jpp_defaults.grid_size);
  EXPECT_EQ(detector.jpp.texture_gate, 0.0);
  EXPECT_EQ(detector.dense.sgbm.num_disparities, dense_defaults.sgbm.num_disparities);
  EXPECT_EQ(detector.dense.min_obstacle_fraction, dense_defaults.min_obstacle_fraction);
}

TEST(StereoOptions, ShippedExampleConfigNamesEveryDetectorFlag) {
  // The README calls it the parameter list: a flag added without its key
  // (the SGBM tuning and the dense range were) would be missing from it.
  std::ifstream in(IVOA_STEREO_EXAMPLE_CONFIG);
  std::set<std::string> keys;
  for (std::string line; std::getline(in, line);)
    if (const size_t eq = line.find(" = "); eq != std::string::npos && line[0] != '#') keys.insert(line.substr(0, eq));
  CLI::App app;
  DetectorConfig detector;
  add_detector_options(app, detector);
  for (const CLI::Option* option : app.get_options()) {
    if (option->get_lnames().empty() || option->get_lnames()[0] == "help") continue;
    EXPECT_TRUE(keys.count(option->get_lnames()[0])) << "stereo_detector.ini has no key " << option->get_lnames()[0];
  }
}

}  // namespace
}  // namespace ivoa::stereo
