// CauseFinder replays a frame exactly (its verdicts are the recorded ones)
// and blames a mirroring floor for the obstacles JPP-C sees in it.
#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "ivoa/causes/cause_finder.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/query_grid.hpp"
#include "ivoa/obstacle_grid_t.hpp"
#include "ivoa/sim/elements.hpp"
#include "ivoa/sim/messages.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"
#include "ivoa/sim_ground_truth_t.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::causes {
namespace {

using GT = sim_ground_truth_t;
using Labels = introspection_labels_t;
constexpr int64_t kStart = 1'700'000'000'000'000;

// A polished stone floor mirrors a poster wall: stereo sees the mirror
// image below the floor (sim tests: ReflectiveFloorMisleadsStereo...).
sim::SceneSpec mirroring_floor() {
  sim::SceneSpec spec = sim::make_bare_spec(sim::Environment::kIndoor, "polished_stone");
  spec.elements.push_back(sim::elements::wall({4.0, -4}, {4.0, 4}, "poster_wall"));
  return spec;
}

// The frame as the driver renders it at session time 0, and labels for it:
// the floor is free everywhere, so every cell JPP-C calls an obstacle is an FP.
struct LabelledFrame {
  Labels labels;
  sim::Pose2D pose;
  int fp = 0;
};

LabelledFrame label_frame(const sim::SceneSpec& spec) {
  const sim::Scene scene = sim::generate_scene(spec, 1);
  const sim::Simulator simulator(scene, sim::SimulatorConfig{sim::make_sim_rig(), {}, {}, false});
  sim::Trajectory trajectory(scene, 1);
  sim::RenderRequest request;
  request.stereo_pose = request.depth_pose = trajectory.pose_at(0);
  request.motion = trajectory.twist_at(0);
  const stereo_image_t msg =
      sim::make_stereo_message(simulator.render(request), kStart, 0, image_t::PIXEL_FORMAT_BAYER_RGGB);
  auto detector = stereo::make_detector("jppc", simulator.rig(), {});
  detector->set_frame(decode_image(msg.left), decode_image(msg.right));
  QueryGridConfig grid_config;
  grid_config.x_max = 2.5;
  const QueryGrid grid(grid_config, CameraModel(simulator.rig().left, simulator.rig().left_to_robot));
  LabelledFrame out;
  out.pose = request.stereo_pose;
  Labels& l = out.labels;
  l = Labels{};  // lcm-gen types leave numbers uninitialised
  l.utime = kStart;
  l.detector = "jppc";
  l.safety_radius = grid_config.safety_radius;
  for (int i = 0; i < grid.size(); ++i) {
    const QueryCell& c = grid.cell(i);
    if (!c.in_image) continue;
    const int8_t state = stereo::to_state(detector->check(c.x, c.y, l.safety_radius));
    out.fp += state == obstacle_grid_t::STATE_OBSTACLE;
    l.label.push_back(label_of_verdicts(state, obstacle_grid_t::STATE_FREE));  // depth: all free
    l.stereo_state.push_back(state);
    l.depth_state.push_back(obstacle_grid_t::STATE_FREE);
    l.x.push_back(static_cast<float>(c.x));
    l.y.push_back(static_cast<float>(c.y));
    l.u.push_back(static_cast<float>(c.u));
    l.v.push_back(static_cast<float>(c.v));
  }
  l.num_cells = l.num_x = static_cast<int32_t>(l.label.size());  // the in-image cells, as a 1 x n grid
  l.num_y = 1;
  return out;
}

CauseFinder make_finder(const sim::SceneSpec& spec) {
  SessionTiming timing;
  timing.start_utime = kStart;
  return CauseFinder(spec, 1, sim::make_sim_rig(), timing, "jppc", {});
}

TEST(CauseFinder, ReplaysTheFrameAndBlamesTheReflection) {
  const sim::SceneSpec spec = mirroring_floor();
  const LabelledFrame frame = label_frame(spec);
  ASSERT_GE(frame.fp, 5) << "JPP-C should see obstacles in the mirror image";
  CauseFinder finder = make_finder(spec);
  EXPECT_TRUE(finder.testable() & GT::PHENOMENON_REFLECTION);
  const std::vector<CellCause> cells = finder.explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB);
  ASSERT_EQ(static_cast<int>(cells.size()), frame.fp) << "one entry per failure cell";
  int reflection = 0;
  for (const CellCause& c : cells) {
    EXPECT_EQ(c.label, Labels::LABEL_FP);
    EXPECT_TRUE(c.reproduced()) << "cell " << c.cell;
    EXPECT_EQ(c.tested, finder.testable());
    EXPECT_EQ(c.causes & ~c.tested, 0);
    reflection += (c.causes & GT::PHENOMENON_REFLECTION) != 0;
  }
  EXPECT_GE(reflection, 0.8 * frame.fp) << "without the mirror image the floor is free";
}

TEST(CauseFinder, RefusesAFrameItCannotReproduce) {
  const sim::SceneSpec spec = mirroring_floor();
  LabelledFrame frame = label_frame(spec);
  CauseFinder finder = make_finder(spec);
  const sim::Pose2D recorded = frame.pose;
  frame.pose.x += 0.05;  // not where the trajectory was
  EXPECT_THROW(finder.explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB), ReplayError);
  frame.pose.x = std::numeric_limits<double>::quiet_NaN();  // used to pass the pose comparison
  EXPECT_THROW(finder.explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB), ReplayError);
  // Five hours after the start: stepping the trajectory there hung.
  frame.pose = recorded;
  frame.labels.utime = kStart + 5 * 3600 * int64_t{1'000'000};
  try {
    finder.explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB);
    FAIL() << "a frame 5 h after the start was replayed";
  } catch (const ReplayError& e) {
    EXPECT_NE(std::string(e.what()).find("18000 s after the session's start utime"), std::string::npos) << e.what();
  }
}

// A label value outside -1..3 indexed the tallies: heap corruption (label
// 13: "free(): invalid size"), or silently wrong counts.
TEST(CauseFinder, RefusesLabelsItCannotExplain) {
  const sim::SceneSpec spec = mirroring_floor();
  LabelledFrame frame = label_frame(spec);
  CauseFinder finder = make_finder(spec);
  Labels bad = frame.labels;
  bad.label[1] = 13;
  try {
    finder.explain(bad, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB);
    FAIL() << "label 13 accepted";
  } catch (const ReplayError& e) {
    EXPECT_NE(std::string(e.what()).find("cell 1 has label 13, not -1..3"), std::string::npos) << e.what();
  }
  bad = frame.labels;
  bad.x[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(check_labels(bad), std::invalid_argument);
  bad = frame.labels;
  bad.safety_radius = -1;
  EXPECT_THROW(check_labels(bad), std::invalid_argument);
  EXPECT_NO_THROW(check_labels(frame.labels));
}

TEST(CauseFinder, FrameWithoutFailuresRendersNothing) {
  const sim::SceneSpec spec = mirroring_floor();
  LabelledFrame frame = label_frame(spec);
  for (auto& label : frame.labels.label) label = Labels::LABEL_TN;
  for (auto& state : frame.labels.stereo_state) state = obstacle_grid_t::STATE_FREE;
  frame.pose.x += 1.0;  // would be refused if it were rendered
  EXPECT_TRUE(make_finder(spec).explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB).empty());
}

// A variant that behaves like the detector fixes nothing and breaks
// nothing; one that matches anything fixes the false obstacles; one that
// matches nothing calls every free cell an obstacle. Each is tallied apart.
TEST(CauseFinder, TriesOtherDetectorSettingsOnTheSameFrame) {
  const sim::SceneSpec spec = mirroring_floor();
  const LabelledFrame frame = label_frame(spec);
  ASSERT_GE(frame.fp, 5);
  DetectorVariant same{"same", {}}, anything{"matches anything", {}}, nothing{"matches nothing", {}};
  anything.config.jpp.conf_pos_thresh = 10.0;  // above any window cost (at most 2.41)
  nothing.config.jpp.conf_pos_thresh = 1e-9;   // below any cost but a perfect match
  SessionTiming timing;
  timing.start_utime = kStart;
  CauseFinder finder(spec, 1, sim::make_sim_rig(), timing, "jppc", {}, {same, anything, nothing});
  const std::vector<CellCause> cells = finder.explain(frame.labels, frame.pose, image_t::PIXEL_FORMAT_BAYER_RGGB);
  ASSERT_EQ(static_cast<int>(cells.size()), frame.fp);
  int64_t fixed = 0;
  for (const CellCause& c : cells) {
    EXPECT_EQ(c.fixed_by & 0b101, 0) << "cell " << c.cell;
    fixed += c.fixed_by == 0b010;
  }

  const std::vector<VariantTally>& t = finder.variant_tallies();
  ASSERT_EQ(t.size(), 3u);
  const auto fp = static_cast<size_t>(Labels::LABEL_FP), tn = static_cast<size_t>(Labels::LABEL_TN);
  const auto tn_cells = std::count(frame.labels.label.begin(), frame.labels.label.end(), Labels::LABEL_TN);
  for (const VariantTally& v : t) {
    EXPECT_EQ(v.cells[fp], frame.fp);
    EXPECT_EQ(v.cells[tn], tn_cells);
  }
  EXPECT_EQ(t[0].right[fp], 0);
  EXPECT_EQ(t[0].wrong[tn], 0);
  // Where a sample's window leaves the image, only the failed match made
  // the cell an obstacle: matching anything, it has no verdict.
  EXPECT_EQ(t[1].right[fp], fixed);
  EXPECT_GE(fixed, 0.8 * frame.fp);
  EXPECT_EQ(t[1].wrong[fp] + t[1].right[fp], fixed) << "none still an obstacle";
  EXPECT_EQ(t[1].wrong[tn], 0);
  EXPECT_EQ(t[2].right[fp], 0);
  EXPECT_GE(t[2].wrong[tn], tn_cells / 2) << "matching nothing, the floor is an obstacle";
  EXPECT_EQ(variant_names({same, anything, nothing}, 0b101), "same+matches nothing");
}

TEST(CauseFinder, RefusesVariantNamesThatAreNotCsvFields) {
  EXPECT_NO_THROW(check_variant_name("full resolution"));
  for (const char* bad : {"", "a,b", "a+b", "say \"hi\"", "two\nlines"})
    EXPECT_THROW(check_variant_name(bad), std::invalid_argument) << bad;
}

TEST(CauseFinder, NamesCombinationsOfPhenomena) {
  EXPECT_EQ(phenomena_names(0), "none found");
  EXPECT_EQ(phenomena_names(GT::PHENOMENON_REFLECTION | GT::PHENOMENON_DARK_STRIPE), "reflection+dark stripe");
  CellCause c;
  c.label = Labels::LABEL_FN;
  c.stereo_state = c.replayed_state = obstacle_grid_t::STATE_FREE;
  c.tested = GT::PHENOMENON_TEXTURELESS | GT::PHENOMENON_DARK_STRIPE;
  EXPECT_EQ(describe(c), "none found");
  c.jointly = true;
  EXPECT_EQ(describe(c), "together: textureless+dark stripe");
  c.causes = GT::PHENOMENON_DARK_STRIPE;
  EXPECT_EQ(describe(c), "dark stripe");
  c.replayed_state = obstacle_grid_t::STATE_OBSTACLE;
  EXPECT_EQ(describe(c), "not reproduced");
}

TEST(SessionRate, FramesSkippedInRealTimeDoNotSlowIt) {
  const int64_t t0 = 1700000000000000;
  std::vector<int64_t> at_4hz;
  for (int k = 0; k <= 16; ++k)
    if (k != 4) at_4hz.push_back(t0 + 250000 * k);  // frame 4 skipped: 16 frames over 4 s
  EXPECT_DOUBLE_EQ(rate_from_frame_times(at_4hz), 4.0);
  // 3 Hz stamps round to the microsecond: gaps of 333333 and 333334 us
  std::vector<int64_t> at_3hz;
  for (int k : {0, 1, 2, 5, 6, 7, 300}) at_3hz.push_back(t0 + std::llround(k * 1e6 / 3.0));
  EXPECT_NEAR(rate_from_frame_times(at_3hz), 3.0, 1e-9);
  EXPECT_EQ(rate_from_frame_times({t0}), 1.0);
}

// A --rate given is checked against the frame times: whole periods of it,
// to the microsecond rounding of 30 Hz stamps; a multiple fits too.
TEST(SessionRate, AGivenRateFitsFrameTimesOfWholePeriods) {
  const int64_t t0 = 1700000000000000;
  std::vector<int64_t> at_30hz;
  for (int k : {0, 1, 2, 4, 7, 8, 300}) at_30hz.push_back(t0 + std::llround(k * 1e6 / 30.0));
  EXPECT_TRUE(frame_times_fit_rate(at_30hz, 30.0));
  EXPECT_TRUE(frame_times_fit_rate(at_30hz, 60.0));
  EXPECT_FALSE(frame_times_fit_rate(at_30hz, 15.0));
  EXPECT_FALSE(frame_times_fit_rate(at_30hz, 29.99));
}

// A simulator too slow for its --rate publishes every second or third
// frame: no gap is one period, and the shortest (two) would halve the rate.
TEST(SessionRate, NoTwoFramesInARowStillGiveTheRate) {
  const int64_t t0 = 1700000000000000;
  std::vector<int64_t> at_5hz;  // frames 0, 2, 5, 7, 10, ...: gaps of 2 and 3 periods
  for (int k = 0; k <= 50; k += (k % 5 == 0) ? 2 : 3) at_5hz.push_back(t0 + 200000 * k);
  EXPECT_DOUBLE_EQ(rate_from_frame_times(at_5hz), 5.0);
  std::vector<int64_t> at_30hz;  // stamps rounded to the microsecond; gaps of 3, 4 and 5 periods
  for (int k : {0, 3, 7, 12, 15, 19, 24, 27, 31, 300}) at_30hz.push_back(t0 + std::llround(k * 1e6 / 30.0));
  EXPECT_NEAR(rate_from_frame_times(at_30hz), 30.0, 1e-6);
  std::vector<int64_t> at_10hz;  // 269 periods (the 1e6 / 10 period, on uneven gaps)
  for (int k : {0, 7, 11, 13, 200, 269}) at_10hz.push_back(t0 + 100000 * k);
  EXPECT_DOUBLE_EQ(rate_from_frame_times(at_10hz), 10.0);
}

}  // namespace
}  // namespace ivoa::causes
