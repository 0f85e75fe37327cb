// Building a dataset from a short simulated session: patches are the pixels
// of the frames they came from, labels equal an independent recomputation
// (detector + monitor + Algorithm 1 per frame, without the pairing
// pipeline), and recorded labels are taken as they are.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <limits>

#include <gtest/gtest.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/ground_warp.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/dataset/builder.hpp"
#include "ivoa/dataset/patch.hpp"
#include "ivoa/logio/log_format.hpp"
#include "ivoa/logio/log_reader.hpp"
#include "ivoa/logio/log_writer.hpp"
#include "ivoa/monitor/depth_monitor.hpp"
#include "ivoa/monitor/labeler.hpp"
#include "ivoa/stereo/detector.hpp"
#include "ivoa/stereo/jppc_detector.hpp"
#include "sim_log.hpp"
#include "test_rig.hpp"

namespace ivoa::dataset {
namespace {

const std::string kScene = std::string(IVOA_SCENES_DIR) + "/indoor_office.yaml";
constexpr int kTN = introspection_labels_t::LABEL_TN;

// Labels of one frame computed directly, cell by cell.
introspection_labels_t recompute_labels(const RigCalibration& rig, const sim::SimFrame& frame, int64_t utime,
                                        int64_t depth_utime) {
  const QueryGrid grid(QueryGridConfig{}, RigGeometry(rig).left);
  const stereo::DetectorConfig config;
  auto detector = stereo::make_detector("jppc", rig, config);
  detector->set_frame(frame.left, frame.right);
  obstacle_grid_t stereo = make_obstacle_grid(grid, "jppc", utime);
  detector->evaluate(grid, stereo);
  obstacle_grid_t depth = make_obstacle_grid(grid, "depth_monitor", utime);
  depth.depth_utime = depth_utime;
  monitor::DepthMonitor(rig).evaluate(frame.depth_mm, grid, depth);
  return monitor::label_frame(stereo, depth);
}

// Sets cell i's label and the two verdicts that give it (Algorithm 1;
// readers refuse a label its verdicts do not give).
void set_label(introspection_labels_t& labels, size_t i, int8_t label) {
  constexpr int8_t kFree = obstacle_grid_t::STATE_FREE, kObstacle = obstacle_grid_t::STATE_OBSTACLE;
  labels.label[i] = label;
  const bool stereo_obstacle = label == introspection_labels_t::LABEL_TP || label == introspection_labels_t::LABEL_FP;
  const bool depth_obstacle = label == introspection_labels_t::LABEL_TP || label == introspection_labels_t::LABEL_FN;
  labels.stereo_state[i] = label < 0 ? obstacle_grid_t::STATE_UNKNOWN : stereo_obstacle ? kObstacle : kFree;
  labels.depth_state[i] = depth_obstacle ? kObstacle : kFree;
}

// A 5-frame log whose recorded labels are a recognisable pattern (cell
// index mod 4 where the cell is in the image), so a builder that relabels
// shows; returns (utime, cell) -> label.
std::map<std::pair<int64_t, int>, int> write_patterned_labels_log(const std::string& log_path) {
  std::map<std::pair<int64_t, int>, int> recorded;
  test::write_sim_log(log_path, kScene, 5, 4, [&](Bus& bus, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    const QueryGrid grid(QueryGridConfig{}, RigGeometry(sim::make_sim_rig()).left);
    introspection_labels_t labels = recompute_labels(sim::make_sim_rig(), frame, f.utime, f.depth_utime);
    for (size_t i = 0; i < labels.label.size(); ++i) {
      set_label(labels, i, static_cast<int8_t>(grid.cell(static_cast<int>(i)).in_image ? i % 4 : -1));
      if (labels.label[i] >= 0) recorded[{f.utime, static_cast<int>(i)}] = labels.label[i];
    }
    bus.publish(channels::kIntrospectionLabels, labels);
  });
  return recorded;
}

// Builds session `name` under `root` from one log and opens it.
SessionReader build_session(const std::string& root, const std::string& name, const std::string& log,
                            const BuildOptions& options) {
  SessionBuilder builder(root, name, options);
  builder.add_log(log);
  builder.finish();
  return SessionReader(root + "/" + name);
}

struct Expected {
  std::map<std::pair<int64_t, int>, int> labels;  // (utime, cell) -> label, patch inside the image
  std::map<int64_t, cv::Mat> left;
};

TEST(DatasetBuilder, RerunLabelsMatchAnIndependentRecomputationAndPatchesTheFrames) {
  test::TempDir dir;
  const std::string log_path = dir.file("office_s3.lcmlog");
  Expected expected;
  test::write_sim_log(log_path, kScene, 3, 8, [&](Bus&, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    expected.left[f.utime] = frame.left.clone();
    const auto labels = recompute_labels(sim::make_sim_rig(), frame, f.utime, f.depth_utime);
    for (size_t i = 0; i < labels.label.size(); ++i)
      if (labels.label[i] != introspection_labels_t::LABEL_NONE &&
          !extract_patch(frame.left, labels.u[i], labels.v[i], 100).empty())
        expected.labels[{f.utime, static_cast<int>(i)}] = labels.label[i];
  });
  ASSERT_GT(expected.labels.size(), 50u);

  BuildOptions options;
  options.labels = "jppc";
  SessionBuilder builder(dir.file("data"), "office_s3", options);
  builder.add_log(log_path);
  const BuildReport report = builder.finish();
  EXPECT_TRUE(report.problems.empty());
  EXPECT_EQ(report.stereo_frames, 8);
  EXPECT_EQ(report.frames_unmatched, 0);
  EXPECT_EQ(pairing_warning(report, options.pairing), "");

  const SessionReader session(dir.file("data") + "/office_s3");
  EXPECT_EQ(session.info().detector, "jppc");
  EXPECT_EQ(session.info().labels_from, "rerun");
  EXPECT_EQ(session.info().scene, "indoor_office");
  EXPECT_EQ(session.info().seed, 3);
  EXPECT_EQ(session.info().environment, "indoor");
  EXPECT_EQ(session.info().image_size, cv::Size(sim::make_sim_rig().left.width, sim::make_sim_rig().left.height))
      << "what the patches were cut from, for the model to record";
  ASSERT_EQ(session.size(), expected.labels.size());
  for (size_t k = 0; k < session.size(); ++k) {
    const SampleRecord& s = session.samples()[k];
    const auto it = expected.labels.find({s.utime, s.cell});
    ASSERT_NE(it, expected.labels.end()) << "unexpected sample " << s.utime << " cell " << s.cell;
    EXPECT_EQ(s.label, it->second) << "cell " << s.cell;
    EXPECT_EQ(s.depth_utime, s.utime + 4000);
    const cv::Mat crop = extract_patch(expected.left.at(s.utime), s.u, s.v, 100);
    EXPECT_EQ(cv::norm(session.patch(k), crop, cv::NORM_INF), 0) << "patch " << k;
  }
}

TEST(DatasetBuilder, StoresTheDetectorsEvidenceAndNaNWhereTheRecordedVerdictDiffers) {
  test::TempDir dir;
  const std::string log_path = dir.file("ev.lcmlog");
  const RigCalibration rig = sim::make_sim_rig();
  std::map<std::pair<int64_t, int>, std::vector<float>> expected;
  std::pair<int64_t, int> flipped{-1, -1};
  test::write_sim_log(log_path, kScene, 5, 3, [&](Bus& bus, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    introspection_labels_t labels = recompute_labels(rig, frame, f.utime, f.depth_utime);
    stereo::JppcDetector jppc(rig, stereo::JppConfig{});
    jppc.set_frame(frame.left, frame.right);
    for (size_t i = 0; i < labels.label.size(); ++i) {
      if (labels.label[i] == introspection_labels_t::LABEL_NONE) continue;
      expected[{f.utime, static_cast<int>(i)}] = jppc.evidence(labels.x[i], labels.y[i], labels.safety_radius).values;
      if (flipped.first < 0) {  // as if recorded with other settings
        labels.stereo_state[i] = static_cast<int8_t>(1 - labels.stereo_state[i]);
        labels.label[i] = label_of_verdicts(labels.stereo_state[i], labels.depth_state[i]);
        flipped = {f.utime, static_cast<int>(i)};
      }
    }
    bus.publish(channels::kIntrospectionLabels, labels);
  });
  SessionBuilder builder(dir.file("data"), "ev", BuildOptions{});  // recorded labels
  builder.add_log(log_path);
  EXPECT_EQ(builder.finish().evidence_mismatches, 1);
  const SessionReader session(dir.file("data") + "/ev");
  ASSERT_EQ(session.info().evidence_size, 15);
  size_t compared = 0;
  for (size_t k = 0; k < session.size(); ++k) {
    const SampleRecord& s = session.samples()[k];
    const float* e = session.evidence(k);
    const std::vector<float>& want = expected.at({s.utime, s.cell});
    ASSERT_EQ(want.size(), 15u);
    for (size_t j = 0; j < 15; ++j) {
      if (std::make_pair(s.utime, s.cell) == flipped || std::isnan(want[j])) {
        EXPECT_TRUE(std::isnan(e[j])) << k;
      } else {
        EXPECT_EQ(e[j], want[j]) << "sample " << k << " ground sample " << j;
      }
    }
    ++compared;
  }
  EXPECT_GT(compared, 20u);

  BuildOptions off;
  off.evidence = false;
  EXPECT_EQ(build_session(dir.file("data"), "off", log_path, off).info().evidence_size, 0);
  BuildOptions dense;
  dense.labels = "dense";
  const SessionReader dense_session = build_session(dir.file("data"), "dense", log_path, dense);
  EXPECT_EQ(dense_session.info().evidence_size, 0) << "the dense detector keeps no evidence";
  EXPECT_GT(dense_session.size(), 0u);
}

TEST(DatasetBuilder, TwoViewPatchesStackTheGroundWarpedRightView) {
  test::TempDir dir;
  const std::string log_path = dir.file("two_s4.lcmlog");
  std::map<int64_t, std::pair<cv::Mat, cv::Mat>> frames;  // utime -> left, right
  test::write_sim_log(log_path, kScene, 4, 3, [&](Bus&, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    frames[f.utime] = {frame.left.clone(), frame.right.clone()};
  });
  BuildOptions options;
  options.labels = "jppc";
  options.views = 2;
  const SessionReader session = build_session(dir.file("data"), "two", log_path, options);
  EXPECT_EQ(session.info().views, 2);
  ASSERT_GT(session.size(), 20u);
  const GroundWarp warp(sim::make_sim_rig());
  for (size_t k = 0; k < session.size(); k += 7) {
    const SampleRecord& s = session.samples()[k];
    const auto& [left, right] = frames.at(s.utime);
    EXPECT_EQ(cv::norm(session.left_patch(k), extract_patch(left, s.u, s.v, 100), cv::NORM_INF), 0) << k;
    const cv::Mat warped = extract_patch(warp.warp(right), s.u, s.v, 100);
    EXPECT_EQ(cv::norm(session.patch(k).rowRange(100, 200), warped, cv::NORM_INF), 0) << k;
  }
  options.views = 3;
  EXPECT_THROW(SessionBuilder(dir.file("data"), "three", options), std::invalid_argument);
}

TEST(DatasetBuilder, RecordedLabelsAreUsedAsRecorded) {
  test::TempDir dir;
  const std::string log_path = dir.file("rec.lcmlog");
  const auto recorded = write_patterned_labels_log(log_path);
  const BuildOptions recorded_options;  // labels: recorded
  const SessionReader session = build_session(dir.file("data"), "rec", log_path, recorded_options);
  EXPECT_EQ(session.info().labels_from, "recorded");
  ASSERT_EQ(session.size(), recorded.size());
  for (const auto& s : session.samples()) EXPECT_EQ(s.label, (recorded.at({s.utime, s.cell})));
}

// A session records the size of the frames its patches were cut from, which
// a model trained on it records in turn; frames of another size later (a
// second camera's log given to the same session) are counted, for the tool
// to say that the model will not know them.
// The session's size is that of the frames its samples come from, whichever
// log comes first; frames of another size are counted, labelled or not.
TEST(DatasetBuilder, FramesOfAnotherSizeThanTheSessionsAreCounted) {
  test::TempDir dir;
  const std::string log_path = dir.file("rec.lcmlog");
  write_patterned_labels_log(log_path);
  const std::string other_log = dir.file("other_camera.lcmlog");
  {
    Bus bus("file://" + other_log + "?mode=w");
    rig_calibration_t calibration = to_message(sim::make_sim_rig(), 89'900'000);
    bus.publish(channels::kRigCalibration, calibration);
    cv::Mat small(240, 320, CV_8UC3, cv::Scalar::all(90));
    for (int64_t utime : {90'000'000, 90'100'000}) {
      stereo_image_t frame{};
      frame.utime = utime;
      frame.left = encode_image(small, image_t::PIXEL_FORMAT_BGR, utime);
      frame.right = frame.left;
      bus.publish(channels::kStereoImages, frame);
    }
  }
  SessionBuilder builder(dir.file("data"), "mixed", BuildOptions{});
  builder.add_log(log_path);
  builder.add_log(other_log);
  const BuildReport report = builder.finish();
  const cv::Size sim_camera(sim::make_sim_rig().left.width, sim::make_sim_rig().left.height);
  EXPECT_EQ(report.image_size, sim_camera);
  EXPECT_EQ(report.frames_other_size, 2);
  EXPECT_EQ(SessionReader(dir.file("data") + "/mixed").info().image_size, sim_camera);

  SessionBuilder other_first(dir.file("data"), "other_first", BuildOptions{});
  other_first.add_log(other_log);
  other_first.add_log(log_path);
  const BuildReport reversed = other_first.finish();
  EXPECT_EQ(reversed.image_size, sim_camera);
  EXPECT_EQ(reversed.frames_other_size, 2);
  EXPECT_EQ(SessionReader(dir.file("data") + "/other_first").info().image_size, sim_camera);
}

// A recorded labels message the session cannot store is skipped, named by
// its byte offset, and the rest built: a label of 9 or a NaN position ended
// the whole build; a patch_size of -64 wrote a session no reader opens; a
// label its verdicts do not give (TP where both said free) was stored.
TEST(DatasetBuilder, RecordedLabelsTheSessionCannotStoreAreSkipped) {
  test::TempDir dir;
  const std::string log_path = dir.file("rec.lcmlog");
  int frame = 0;
  test::write_sim_log(log_path, kScene, 5, 5, [&](Bus& bus, const test::SimLogFrame& f, const sim::SimFrame& rendered) {
    introspection_labels_t labels = recompute_labels(sim::make_sim_rig(), rendered, f.utime, f.depth_utime);
    if (frame == 1) labels.label[3] = 9;
    if (frame == 2) labels.patch_size = -64;
    if (frame == 3) labels.x[0] = std::numeric_limits<float>::quiet_NaN();
    if (frame == 4)
      *std::find(labels.label.begin(), labels.label.end(), introspection_labels_t::LABEL_TN) =
          introspection_labels_t::LABEL_TP;
    ++frame;
    bus.publish(channels::kIntrospectionLabels, labels);
  });
  SessionBuilder builder(dir.file("data"), "rec", BuildOptions{});
  builder.add_log(log_path);
  const BuildReport report = builder.finish();
  EXPECT_EQ(report.bad_messages, 4) << fmt::format("{}", fmt::join(report.problems, "\n"));
  const auto said = [&](const std::string& what) {
    return std::any_of(report.problems.begin(), report.problems.end(),
                       [&](const std::string& p) { return p.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(said("cell 3 has label 9, not -1..3, skipped"));
  EXPECT_TRUE(said("patch_size -64 is not 1-4096, skipped"));
  EXPECT_TRUE(said("cell 0 has no finite position, skipped"));
  EXPECT_TRUE(said("has label 0, which its verdicts (stereo 0, depth 0) do not give, skipped"));
  EXPECT_TRUE(said("INTROSPECTION_LABELS at byte "));
  const SessionReader session(dir.file("data") + "/rec");
  EXPECT_EQ(session.info().frames, 1);
  EXPECT_EQ(session.info().patch_size, 100);
}

// A log given twice (or frames recorded twice) stores each frame once.
TEST(DatasetBuilder, AFrameGivenTwiceIsStoredOnce) {
  test::TempDir dir;
  const std::string log_path = dir.file("rec.lcmlog");
  const auto recorded = write_patterned_labels_log(log_path);
  for (const char* labels : {"recorded", "jppc"}) {
    BuildOptions options;
    options.labels = labels;
    SessionBuilder builder(dir.file("data"), "twice", options);
    builder.add_log(log_path);
    builder.add_log(log_path);
    const BuildReport report = builder.finish();
    EXPECT_EQ(report.stereo_frames, 8) << labels;
    const SessionReader session(dir.file("data") + "/twice");
    EXPECT_EQ(session.info().frames, 4) << labels;
    std::set<std::pair<int64_t, int>> cells;
    for (const auto& s : session.samples()) EXPECT_TRUE(cells.insert({s.utime, s.cell}).second) << labels;
    if (std::string(labels) == "recorded") {  // (re-run, the pairer sets the replayed frames aside as repeats)
      EXPECT_EQ(report.frames_repeated, 4);
      EXPECT_EQ(session.size(), recorded.size());
    }
  }
}

// Re-run labels beside a depth camera slower than the stereo one: most
// frames unpaired was said only as a count, and the session came out tiny.
TEST(DatasetBuilder, MostFramesUnpairedIsSaidWithTheFlagThatPairsThem) {
  BuildReport report;
  report.stereo_frames = 441, report.frames_labelled = 1, report.frames_unmatched = 440;
  monitor::PairingConfig pairing;
  const std::string said = pairing_warning(report, pairing);
  EXPECT_NE(said.find("440 of its 441 stereo frames have no depth frame within 16.7 ms (--sync-tolerance-us)"),
            std::string::npos)
      << said;
  report.frames_labelled = 437, report.frames_unmatched = 4;  // a start-up's few
  EXPECT_EQ(pairing_warning(report, pairing), "");
  report.frames_labelled = 50, report.frames_unmatched = 100;  // most paired, if few gave samples
  EXPECT_EQ(pairing_warning(report, pairing), "");
}

// session.json names every log read: a split recording's later parts
// were left out, since the session was opened on the first part's samples.
TEST(DatasetBuilder, EveryLogReadIsNamedInTheSession) {
  test::TempDir dir;
  const std::string first = dir.file("rec.lcmlog"), second = dir.file("rec.lcmlog.01");
  write_patterned_labels_log(first);
  std::filesystem::copy_file(first, second);
  SessionBuilder builder(dir.file("data"), "parts", BuildOptions{});
  builder.add_log(first);
  builder.add_log(second);
  builder.finish();
  const SessionReader session(dir.file("data") + "/parts");
  EXPECT_EQ(session.info().logs, (std::vector<std::string>{first, second}));
}

TEST(DatasetBuilder, KeepTnStoresAFractionOfTnCellsTheSameOnesEveryBuild) {
  test::TempDir dir;
  const std::string log_path = dir.file("thin.lcmlog");
  const auto recorded = write_patterned_labels_log(log_path);
  int64_t tn = 0;
  for (const auto& [cell, label] : recorded) tn += label == kTN;
  // Squares this large leave the image near its border: those cells are
  // not stored either way, so they do not count as left out.
  BuildOptions every_tn;
  every_tn.recorded_patch_size = 300;
  BuildOptions thin = every_tn;
  thin.keep_tn = 0.5;
  const auto cells_of = [](const SessionReader& r, bool want_tn) {
    std::set<std::pair<int64_t, int>> cells;
    for (const auto& s : r.samples())
      if ((s.label == kTN) == want_tn) cells.insert({s.utime, s.cell});
    return cells;
  };
  const SessionReader all = build_session(dir.file("data"), "all", log_path, every_tn);
  const SessionReader a = build_session(dir.file("data"), "a", log_path, thin);
  const SessionReader b = build_session(dir.file("data"), "b", log_path, thin);
  EXPECT_EQ(cells_of(a, false), cells_of(all, false)) << "the other classes are all kept";
  EXPECT_EQ(cells_of(a, true), cells_of(b, true)) << "a rebuild keeps the same TN cells";
  const auto kept = cells_of(a, true), every = cells_of(all, true);
  EXPECT_TRUE(std::includes(every.begin(), every.end(), kept.begin(), kept.end()));
  const auto stored = static_cast<int64_t>(every.size());
  ASSERT_LT(stored, tn) << "no square left the image: the test does not cover that case";
  EXPECT_GT(kept.size(), stored * 3 / 10);
  EXPECT_LT(kept.size(), stored * 7 / 10);
  EXPECT_DOUBLE_EQ(a.info().tn_kept, 0.5);
  EXPECT_EQ(a.info().tn_dropped + static_cast<int64_t>(kept.size()), stored);
  EXPECT_EQ(a.info().class_counts[kTN], static_cast<int64_t>(kept.size()));
  EXPECT_EQ(all.info().tn_dropped, 0);
  BuildOptions none;
  none.keep_tn = 0;
  EXPECT_THROW(SessionBuilder(dir.file("data"), "none", none), std::invalid_argument);
}

TEST(DatasetBuilder, RecordedLabelsCanBeCutWithAnotherPatchSize) {
  test::TempDir dir;
  const std::string log_path = dir.file("rec.lcmlog");
  std::map<int64_t, cv::Mat> left;
  size_t recorded = 0;
  test::write_sim_log(log_path, kScene, 5, 3, [&](Bus& bus, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    introspection_labels_t labels = recompute_labels(sim::make_sim_rig(), frame, f.utime, f.depth_utime);
    for (int8_t l : labels.label) recorded += l != introspection_labels_t::LABEL_NONE;
    left[f.utime] = frame.left;
    bus.publish(channels::kIntrospectionLabels, labels);
  });
  BuildOptions options;  // labels: recorded
  options.recorded_patch_size = 360;
  SessionBuilder builder(dir.file("data"), "rec", options);
  builder.add_log(log_path);
  const BuildReport report = builder.finish();
  const SessionReader session(dir.file("data") + "/rec");
  EXPECT_EQ(session.info().patch_size, 360);
  EXPECT_EQ(session.info().grid.patch_size, 100);  // the grid that labelled the cells
  ASSERT_GT(session.size(), 0u);
  EXPECT_LT(session.size(), recorded);  // some 360 px squares leave the 960x600 image
  EXPECT_EQ(report.patches_outside, static_cast<int64_t>(recorded - session.size())) << "each skipped cell counted";
  for (size_t i = 0; i < session.size(); ++i) {
    const auto& s = session.samples()[i];
    const cv::Mat want = left.at(s.utime)(patch_rect(s.u, s.v, 360));
    ASSERT_EQ(cv::norm(session.left_patch(i), want, cv::NORM_INF), 0) << "sample " << i;
  }
  options.labels = "jppc";  // re-run labels cut grid.patch_size: the override is refused
  EXPECT_THROW(SessionBuilder(dir.file("data"), "rerun", options), std::invalid_argument);
}

TEST(DatasetBuilder, ScaledPatchesShowTheWholeFootprintNearTheRobot) {
  test::TempDir dir;
  const std::string log_path = dir.file("scaled.lcmlog");
  std::map<int64_t, cv::Mat> left;
  std::map<int64_t, introspection_labels_t> recorded;
  test::write_sim_log(log_path, kScene, 5, 3, [&](Bus& bus, const test::SimLogFrame& f, const sim::SimFrame& frame) {
    introspection_labels_t labels = recompute_labels(sim::make_sim_rig(), frame, f.utime, f.depth_utime);
    left[f.utime] = frame.left;
    recorded[f.utime] = labels;
    bus.publish(channels::kIntrospectionLabels, labels);
  });
  BuildOptions options;  // labels: recorded
  const size_t fixed = build_session(dir.file("fixed"), "s", log_path, options).size();
  options.patch_scale = 1.6;
  const SessionReader session = build_session(dir.file("data"), "s", log_path, options);
  EXPECT_EQ(session.info().patch_scale, 1.6);
  EXPECT_EQ(session.info().patch_size, 100);
  EXPECT_EQ(session.size(), fixed);  // a scaled square shrinks to fit: no cell is lost
  int scaled = 0;
  for (size_t i = 0; i < session.size(); ++i) {
    const auto& s = session.samples()[i];
    const auto& labels = recorded.at(s.utime);
    const int side = footprint_patch_sides(labels, 100, {960, 600}, 1.6)[static_cast<size_t>(s.cell)];
    ASSERT_EQ(s.patch_side, side) << "sample " << i;
    scaled += side > 100;
    // The stored patch is the side x side square, shrunk to 100 px; near cells (x < 2 m) are scaled.
    const cv::Mat want = cut_patch(left.at(s.utime), 1, s.u, s.v, side, 100);
    ASSERT_EQ(cv::norm(session.left_patch(i), want, cv::NORM_INF), 0) << "sample " << i;
    if (s.x < 1.9) EXPECT_GT(side, 100) << "x = " << s.x;
    else EXPECT_EQ(side, 100) << "x = " << s.x;
  }
  EXPECT_GT(scaled, 0);
  options.patch_scale = -1;
  EXPECT_THROW(SessionBuilder(dir.file("data"), "bad", options), std::invalid_argument);
}

TEST(DatasetBuilder, EnvironmentComesFromTheSimulatorNotTheSceneName) {
  test::TempDir dir;
  const std::string log_path = dir.file("wet.lcmlog");
  test::write_sim_log(log_path, std::string(IVOA_SCENES_DIR) + "/wet_parking_lot.yaml", 2, 2);
  BuildOptions options;
  options.labels = "jppc";
  EXPECT_EQ(build_session(dir.file("data"), "wet", log_path, options).info().environment, "outdoor");

  options.environment = "indoor";  // the user's word overrides
  EXPECT_EQ(build_session(dir.file("data2"), "wet", log_path, options).info().environment, "indoor");
}

TEST(DatasetBuilder, TruncatedLogKeepsWhatCameBeforeAndSaysWhere) {
  test::TempDir dir;
  const std::string log_path = dir.file("cut.lcmlog");
  test::write_sim_log(log_path, kScene, 4, 6);
  const auto size = std::filesystem::file_size(log_path);
  std::filesystem::resize_file(log_path, size - size / 4);  // lose the last quarter mid-event
  BuildOptions options;
  options.labels = "jppc";
  SessionBuilder builder(dir.file("data"), "cut", options);
  builder.add_log(log_path);
  const BuildReport report = builder.finish();
  ASSERT_FALSE(report.problems.empty());
  EXPECT_NE(report.problems[0].find("byte "), std::string::npos) << report.problems[0];
  EXPECT_GE(report.stereo_frames, 3);
  EXPECT_GT(report.samples, 0);
}

// Overwrites `bytes` at `offset` of a file.
void overwrite(const std::string& path, uint64_t offset, const std::vector<uint8_t>& bytes) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// The offsets of a log's STEREO_IMAGES events.
std::vector<uint64_t> stereo_event_offsets(const std::string& path) {
  std::vector<uint64_t> out;
  logio::LogReader reader(path);
  logio::LogEvent e;
  while (reader.next(e))
    if (e.channel == channels::kStereoImages) out.push_back(e.offset);
  return out;
}

// One stereo message damaged inside (its source string's length zeroed:
// lcm-gen's decode throws on it) and the framing of a later event broken:
// both are skipped with a problem naming the byte, and the frames after
// each still make the session.
TEST(DatasetBuilder, DamageInsideAMessageOrBetweenEventsIsSkippedAndTheRestBuilt) {
  test::TempDir dir;
  const std::string log_path = dir.file("damaged.lcmlog");
  test::write_sim_log(log_path, kScene, 4, 6);
  const std::vector<uint64_t> stereo = stereo_event_offsets(log_path);
  ASSERT_EQ(stereo.size(), 6u);
  const uint64_t payload = stereo[1] + logio::kEventHeaderBytes + std::string(channels::kStereoImages).size();
  overwrite(log_path, payload + 24, {0, 0, 0, 0});  // after fingerprint, utime and seq
  overwrite(log_path, stereo[3], {0, 0, 0, 0});     // the sync word
  BuildOptions options;
  options.labels = "jppc";
  SessionBuilder builder(dir.file("data"), "damaged", options);
  builder.add_log(log_path);
  const BuildReport report = builder.finish();
  EXPECT_EQ(report.bad_messages, 1);
  EXPECT_EQ(report.stereo_frames, 4);  // frames 0, 2, 4, 5
  const auto said = [&](const std::string& what) {
    return std::any_of(report.problems.begin(), report.problems.end(),
                       [&](const std::string& p) { return p.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(said("STEREO_IMAGES at byte " + std::to_string(stereo[1]) + ": does not decode as ivoa.stereo_image_t"));
  EXPECT_TRUE(said("byte " + std::to_string(stereo[3]) + ": "));
  EXPECT_TRUE(said("skipped to the next good event"));
  EXPECT_EQ(SessionReader(dir.file("data") + "/damaged").info().frames, 4);
}

// A build that ends part-way (here: destroyed before finish) does not list
// a session that holds only part of its logs.
TEST(DatasetBuilder, ASessionWhoseBuildDidNotFinishIsNotListed) {
  test::TempDir dir;
  const std::string log_path = dir.file("s.lcmlog");
  test::write_sim_log(log_path, kScene, 4, 3);
  BuildOptions options;
  options.labels = "jppc";
  {
    SessionBuilder builder(dir.file("data"), "unfinished", options);
    builder.add_log(log_path);
  }
  build_session(dir.file("data"), "whole", log_path, options);
  EXPECT_EQ(list_sessions(dir.file("data")), std::vector<std::string>{"whole"});
  // A rebuild of "whole" that does not finish leaves the session built before as it was.
  const size_t samples = SessionReader(dir.file("data") + "/whole").size();
  const std::string longer = dir.file("longer.lcmlog");
  test::write_sim_log(longer, kScene, 5, 4);
  {
    SessionBuilder rebuild(dir.file("data"), "whole", options);
    rebuild.add_log(longer);
  }
  EXPECT_EQ(SessionReader(dir.file("data") + "/whole").size(), samples);
  EXPECT_EQ(list_sessions(dir.file("data")), std::vector<std::string>{"whole"});
  EXPECT_FALSE(std::filesystem::exists(dir.file("data") + "/.whole.partial"));
  // and one that finishes replaces it
  build_session(dir.file("data"), "whole", longer, options);
  EXPECT_NE(SessionReader(dir.file("data") + "/whole").size(), samples);
}

TEST(DatasetBuilder, LogWithoutCalibrationIsRefused) {
  test::TempDir dir;
  const std::string log_path = dir.file("nocal.lcmlog");
  {
    Bus bus("file://" + log_path + "?mode=w");
    stereo_image_t s;
    bus.publish(channels::kStereoImages, s);
    process_status_t unknown_channel;
    bus.publish("SOMETHING_ELSE", unknown_channel);
  }
  const BuildOptions options;
  SessionBuilder builder(dir.file("data"), "nocal", options);
  try {
    builder.add_log(log_path);
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("no RIG_CALIBRATION"), std::string::npos) << e.what();
  }
}

TEST(DatasetBuilder, FileThatIsNotALogIsNamedAsSuch) {
  test::TempDir dir;
  const std::string path = dir.file("notes.lcmlog");
  std::ofstream(path) << "these are notes, not an LCM log; long enough to hold an event header\n";
  SessionBuilder builder(dir.file("data"), "notes", BuildOptions{});
  try {
    builder.add_log(path);
    FAIL();
  } catch (const DatasetError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("notes.lcmlog: not an LCM log"), std::string::npos) << why;
    EXPECT_NE(why.find("byte 0"), std::string::npos) << why;
  }
}

// A raw log (no depth monitor ran) built with --labels recorded has nothing
// to label from: refused, naming the way out, and the session built before
// under that name is kept, not replaced by an empty one.
TEST(DatasetBuilder, LogWithoutRecordedLabelsIsRefusedAndKeepsTheExistingSession) {
  test::TempDir dir;
  const std::string labelled = dir.file("labelled.lcmlog"), raw = dir.file("raw.lcmlog");
  const auto recorded = write_patterned_labels_log(labelled);
  test::write_sim_log(raw, kScene, 4, 3);
  build_session(dir.file("data"), "s", labelled, BuildOptions{});

  SessionBuilder builder(dir.file("data"), "s", BuildOptions{});
  builder.add_log(raw);
  try {
    builder.finish();
    FAIL() << "a session without labels was written";
  } catch (const DatasetError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("raw.lcmlog: no INTROSPECTION_LABELS message"), std::string::npos) << why;
    EXPECT_NE(why.find("--labels jppc"), std::string::npos) << why;
  }
  EXPECT_EQ(SessionReader(dir.file("data") + "/s").size(), recorded.size());

  BuildOptions rerun;  // and re-labelling needs depth frames
  rerun.labels = "jppc";
  rerun.depth_channel = "NO_SUCH_DEPTH";
  SessionBuilder relabel(dir.file("data"), "s", rerun);
  relabel.add_log(raw);
  EXPECT_THROW(relabel.finish(), DatasetError);
  EXPECT_EQ(SessionReader(dir.file("data") + "/s").size(), recorded.size());

  BuildOptions no_images;  // and labels without the stereo frames they were made on (it wrote 0 samples, exit 0)
  no_images.stereo_channel = "NO_SUCH_STEREO";
  SessionBuilder blind(dir.file("data"), "s", no_images);
  blind.add_log(labelled);
  try {
    blind.finish();
    FAIL() << "a session without images was written";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("labelled.lcmlog: no NO_SUCH_STEREO message"), std::string::npos) << e.what();
  }
  EXPECT_EQ(SessionReader(dir.file("data") + "/s").size(), recorded.size());
}

// Logs that give no sample (here: no depth frame within the tolerance)
// replaced a good session of that name with an empty one, exit 0.
TEST(SessionBuilder, NoSampleAtAllIsAnErrorThatKeepsTheExistingSession) {
  test::TempDir dir;
  const std::string log_path = dir.file("office_s7.lcmlog");
  test::write_sim_log(log_path, kScene, 7, 2);  // depth 4 ms after stereo
  BuildOptions options;
  options.labels = "jppc";
  options.evidence = false;
  SessionBuilder good(dir.file("data"), "s", options);
  good.add_log(log_path);
  const int64_t samples = good.finish().samples;
  ASSERT_GT(samples, 0);
  options.pairing.tolerance_us = 0;
  SessionBuilder unpaired(dir.file("data"), "s", options);
  unpaired.add_log(log_path);
  try {
    unpaired.finish();
    FAIL() << "an empty session was written";
  } catch (const DatasetError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("no sample to store (0 of 2 stereo frames labelled, 2 without a depth frame within 0.0 ms"),
              std::string::npos)
        << why;
    EXPECT_NE(why.find("session 's' not written (an existing one is kept)"), std::string::npos) << why;
  }
  EXPECT_EQ(static_cast<int64_t>(SessionReader(dir.file("data") + "/s").size()), samples);
}

// A copy of the log at `from` with every channel renamed to PREFIX + name,
// as a robot started with renamed channels records it.
void copy_with_renamed_channels(const std::string& from, const std::string& to, const std::string& prefix) {
  logio::LogReader in(from);
  logio::LogWriter out(to);
  logio::LogEvent e;
  while (in.next(e)) out.write(prefix + e.channel, e.timestamp, e.data.data(), e.data.size());
  out.close();
}

// `ivoa-dataset build` reads such a log by the names given, into the same
// samples as the original; without them it finds no frames and says so.
TEST(DatasetBuildCli, RenamedChannelsAreReadWhenNamed) {
  test::TempDir dir;
  const std::string log_path = dir.file("office_s6.lcmlog"), renamed = dir.file("renamed") + "/office_s6.lcmlog";
  std::filesystem::create_directories(dir.file("renamed"));
  test::write_sim_log(log_path, kScene, 6, 3);
  copy_with_renamed_channels(log_path, renamed, "R2_");
  const std::string build = "timeout 120 " IVOA_DATASET_EXE " build --labels jppc --no-evidence --out ";
  ASSERT_EQ(test::run_command(build + dir.file("plain") + " " + log_path).exit_code, kExitOk);
  const auto named = test::run_command(
      build + dir.file("named") +
      " --stereo-channel R2_STEREO_IMAGES --depth-channel R2_DEPTH_IMAGE --calibration-channel R2_RIG_CALIBRATION "
      "--truth-channel R2_SIM_GROUND_TRUTH " +
      renamed);
  ASSERT_EQ(named.exit_code, kExitOk) << named.output;
  const std::string samples = test::read_file(dir.file("plain") + "/office_s6/samples.csv");
  EXPECT_GT(std::count(samples.begin(), samples.end(), '\n'), 20) << samples;
  EXPECT_EQ(test::read_file(dir.file("named") + "/office_s6/samples.csv"), samples);

  const auto unnamed = test::run_command(build + dir.file("unnamed") + " " + renamed);
  EXPECT_NE(unnamed.output.find("no RIG_CALIBRATION message in the log"), std::string::npos) << unnamed.output;
  EXPECT_NE(unnamed.output.find("--calibration-channel"), std::string::npos) << unnamed.output;
  EXPECT_EQ(unnamed.exit_code, kExitBadInput) << unnamed.output;
}

}  // namespace
}  // namespace ivoa::dataset
