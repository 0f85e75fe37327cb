#include "live_score.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "ivoa/logio/log_writer.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::tools {
namespace {

constexpr int8_t kTP = 0, kTN = 1, kFP = 2, kFN = 3, kNone = -1;
constexpr int8_t kFree = obstacle_grid_t::STATE_FREE, kObstacle = obstacle_grid_t::STATE_OBSTACLE;

struct Cell {
  float x, y;
  int8_t label, stereo_state;
};

introspection_labels_t labels_message(int64_t utime, const std::vector<Cell>& cells) {
  introspection_labels_t m{};
  m.utime = utime;
  m.detector = "jppc";
  m.num_cells = m.num_x = static_cast<int32_t>(cells.size());
  m.num_y = 1;
  for (const auto& c : cells) {
    m.label.push_back(c.label);
    m.stereo_state.push_back(c.stereo_state);
    // the monitor's verdict that gives the label (Algorithm 1)
    const bool occupied = c.label == introspection_labels_t::LABEL_TP || c.label == introspection_labels_t::LABEL_FN;
    m.depth_state.push_back(c.label == introspection_labels_t::LABEL_NONE ? obstacle_grid_t::STATE_UNKNOWN
                            : occupied                                    ? obstacle_grid_t::STATE_OBSTACLE
                                                                          : kFree);
    m.x.push_back(c.x);
    m.y.push_back(c.y);
    m.u.push_back(0);
    m.v.push_back(0);
  }
  return m;
}

struct Query {
  float x, y;
  int8_t predicted, announced;
  int8_t verdict, verdict_class, verdict_announced;
};

introspection_t prediction_message(int64_t utime, const std::vector<Query>& queries, double compute_ms = 50) {
  introspection_t m{};
  m.utime = utime;
  m.model_id = "model.pt#abc";
  m.compute_ms = compute_ms;
  m.num_queries = static_cast<int32_t>(queries.size());
  for (const auto& q : queries) {
    m.query_x.push_back(q.x);
    m.query_y.push_back(q.y);
    m.query_u.push_back(0);
    m.query_v.push_back(0);
    m.query_class.push_back(q.predicted);
    m.query_probability.push_back(0.9f);
    m.query_uncertainty.push_back(0.001f);
    m.query_announced.push_back(q.announced);
    m.query_verdict.push_back(q.verdict);
    m.query_verdict_class.push_back(q.verdict_class);
    m.query_p_wrong.push_back(0.1f);
    m.query_p_wrong_variance.push_back(0.001f);
    m.query_verdict_announced.push_back(q.verdict_announced);
  }
  return m;
}

TEST(LiveScorer, MatchesCellsByPositionWhicheverMessageComesFirst) {
  LiveScorer scorer;
  // Frame 1: the prediction before the labels, queries in another order.
  scorer.add(prediction_message(1, {{1.0f, 0.25f, kFP, 1, kObstacle, kFP, 1},
                                    {0.75f, 0.0f, kTN, 0, kFree, kFN, 0},
                                    {2.0f, 0.5f, kTN, 1, kFree, kTN, 1}}));
  scorer.add(labels_message(1, {{0.75f, 0.0f, kTN, kFree},
                                {1.0f, 0.25f, kFP, kObstacle},
                                {2.0f, 0.5f, kNone, kFree},    // no label: not scored
                                {3.0f, 0.0f, kTN, kFree},      // no query there: out of view
                                {3.0f, 0.25f, kTN, kFree}}));  // no query there, in view
  obstacle_grid_t grid{};  // the detector's: (3, 0) is outside the image, (3, 0.25) inside
  grid.utime = 1;
  grid.num_cells = grid.num_x = 2;
  grid.num_y = 1;
  grid.x = {3.0f, 3.0f};
  grid.y = {0.0f, 0.25f};
  grid.in_image = {0, 1};
  grid.state = {kFree, kFree};
  grid.u = grid.v = {0, 0};
  scorer.add(grid);
  // Frame 2: labels only (the introspection dropped it); frame 3: prediction only.
  scorer.add(labels_message(2, {{0.75f, 0.0f, kFN, kFree}}));
  scorer.add(prediction_message(3, {{0.75f, 0.0f, kTN, 1, kFree, kTN, 1}}));
  // The same messages again (a file given twice, a run recorded twice): each frame counts once.
  scorer.add(labels_message(2, {{0.75f, 0.0f, kFN, kFree}}));
  scorer.add(prediction_message(3, {{0.75f, 0.0f, kTN, 1, kFree, kTN, 1}}));
  const LiveScore s = scorer.finish();
  EXPECT_EQ(s.labelled_frames, 2);
  EXPECT_EQ(s.predicted_frames, 2);
  EXPECT_EQ(s.repeated_messages, 2);
  EXPECT_EQ(s.compute.frames, 2);
  EXPECT_EQ(s.scored_frames, 1);
  EXPECT_EQ(s.labelled_cells, 4);
  EXPECT_EQ(s.outside_view_cells, 1);
  EXPECT_EQ(s.unmatched_cells, 1);
  EXPECT_EQ(s.no_grid_cells, 0);
  EXPECT_EQ(s.image.all.total(), 2);
  EXPECT_EQ(s.image.all.counts[kTN][kTN], 1);
  EXPECT_EQ(s.image.all.counts[kFP][kFP], 1);
  EXPECT_EQ(s.image.announced.total(), 1);  // the TN cell was not announced
  EXPECT_EQ(s.given_verdict.all.counts[kTN][kFN], 1);
  EXPECT_EQ(s.given_verdict.announced.counts[kFP][kFP], 1);
  EXPECT_EQ(s.given_verdict.announced.total(), 1);
  EXPECT_EQ(s.verdict_unknown, 0);
  EXPECT_EQ(s.verdict_disagrees, 0);
  EXPECT_EQ(s.models, std::set<std::string>{"model.pt#abc"});
  EXPECT_EQ(s.detectors, std::set<std::string>{"jppc"});
}

TEST(LiveScorer, CountsVerdictsThatAreMissingOrNotTheLabelsOwn) {
  LiveScorer scorer;
  scorer.add(labels_message(5, {{1.0f, 0.0f, kTN, kFree}, {1.25f, 0.0f, kFP, kObstacle}}));
  scorer.add(prediction_message(
      5, {{1.0f, 0.0f, kTN, 1, obstacle_grid_t::STATE_UNKNOWN, kNone, 0}, {1.25f, 0.0f, kFP, 1, kFree, kFN, 1}}));
  const LiveScore s = scorer.finish();
  EXPECT_EQ(s.image.all.total(), 2);
  EXPECT_EQ(s.verdict_unknown, 1);
  EXPECT_EQ(s.verdict_disagrees, 1);
  EXPECT_EQ(s.given_verdict.all.counts[kFP][kFN], 1);
}

// They used to be scored: a class of 7 went nowhere, NaN positions all fell
// on one cell, and a NaN time made the percentiles NaN.
TEST(LiveScorer, MessagesWithValuesItCannotScoreAreLeftOutAndSaidWhy) {
  LiveScorer scorer;
  const std::vector<Cell> cells = {{1.0f, 0.0f, kTN, kFree}, {1.25f, 0.0f, kFP, kObstacle}};
  EXPECT_EQ(scorer.add(labels_message(5, cells)), "");
  EXPECT_EQ(scorer.add(prediction_message(5, {{1.0f, 0.0f, 7, 1, kFree, kTN, 1}})),
            "query 0: class 7 is none of TP 0, TN 1, FP 2, FN 3");
  EXPECT_EQ(scorer.add(prediction_message(5, {{std::nanf(""), 0.0f, kTN, 1, kFree, kTN, 1}})),
            "query 0: position is not finite");
  // Finite but far: millimetre keys overflowed and every cell became one.
  EXPECT_EQ(scorer.add(prediction_message(5, {{1e20f, 0.0f, kTN, 1, kFree, kTN, 1}})),
            "query 0: position is over 1000 km away");
  EXPECT_EQ(scorer.add(labels_message(7, {{0.0f, -3e19f, kTN, kFree}})), "cell 0: position is over 1000 km away");
  EXPECT_EQ(scorer.add(prediction_message(5, {{1.0f, 0.0f, kTN, 1, kFree, 9, 1}})),
            "query 0: class given the verdict 9 is none of -1..3");
  // Drawn by the viewer and scored here before: a NaN pixel, a probability
  // of 7, a negative variance, an announced flag of 5, a P(wrong) of 7.
  introspection_t bad_query = prediction_message(5, {{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}});
  bad_query.query_u[0] = std::nanf("");
  EXPECT_EQ(scorer.add(bad_query).rfind("query 0: pixel (nan, 0.000000) lies outside any image", 0), 0u);
  bad_query = prediction_message(5, {{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}});
  bad_query.query_probability[0] = 7;
  EXPECT_EQ(scorer.add(bad_query), "query 0: probability 7.000000 is not a probability");
  bad_query = prediction_message(5, {{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}});
  bad_query.query_uncertainty[0] = -5;
  EXPECT_EQ(scorer.add(bad_query), "query 0: uncertainty -5.000000 is not a variance");
  EXPECT_EQ(scorer.add(prediction_message(5, {{1.0f, 0.0f, kTN, 5, kFree, kTN, 1}})),
            "query 0: announced flags (5, 1) are not 0 or 1");
  bad_query = prediction_message(5, {{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}});
  bad_query.query_p_wrong[0] = 7;
  EXPECT_EQ(scorer.add(bad_query).rfind("query 0: P(wrong) 7.000000 with variance", 0), 0u);
  EXPECT_EQ(scorer.add(prediction_message(5, {}, std::nan(""))).rfind("compute_ms nan", 0), 0u);
  EXPECT_EQ(scorer.add(prediction_message(5, {}, -1e9)).rfind("compute_ms -1e+09", 0), 0u);
  EXPECT_EQ(scorer.add(prediction_message(5, {}, 1e300)).rfind("compute_ms 1e+300", 0), 0u);
  introspection_labels_t bad_label = labels_message(6, cells);
  bad_label.label[1] = 5;
  EXPECT_EQ(scorer.add(bad_label), "cell 1 has label 5, not -1..3");
  introspection_labels_t bad_shape = labels_message(6, cells);
  bad_shape.num_x = 11;  // 11 x 1 declared for 2 cells: its cells dropped out of the score unsaid
  EXPECT_EQ(scorer.add(bad_shape), "num_x 11 by num_y 1 is not its 2 cells");
  introspection_t nan_heatmap = prediction_message(5, {});
  nan_heatmap.rows = nan_heatmap.cols = nan_heatmap.num_cells = 1;
  nan_heatmap.prob_tp = nan_heatmap.prob_tn = nan_heatmap.prob_fp = {0.25f};
  nan_heatmap.prob_fn = {std::nanf("")};
  nan_heatmap.uncertainty = nan_heatmap.class_variance = {0.0f};
  EXPECT_EQ(scorer.add(nan_heatmap), "heatmap cell 0: prob_fn nan is not a probability");
  obstacle_grid_t grid{};
  grid.utime = 5;
  grid.num_cells = grid.num_x = grid.num_y = 1;
  grid.state = {42};
  grid.x = {1.0f};
  grid.y = {0.0f};
  grid.u = {10.0f};
  grid.v = {10.0f};
  grid.in_image = {1};
  EXPECT_EQ(scorer.add(grid), "cell 0: state 42 is none of FREE 0, OBSTACLE 1, UNKNOWN 2");
  const LiveScore s = scorer.finish();
  EXPECT_EQ(s.predicted_frames, 0);  // none of the predictions was taken
  EXPECT_EQ(s.labelled_frames, 1);
  EXPECT_EQ(s.compute.frames, 0);
}

TEST(LiveScorer, CellsOfAFramePredictedBeforeAnyGridCountApart) {
  LiveScorer scorer;
  scorer.add(labels_message(7, {{1.0f, 0.0f, kTN, kFree}, {1.25f, 0.0f, kFP, kObstacle}}));
  scorer.add(prediction_message(7, {}));  // no grid had reached the introspection: no query cells
  const LiveScore s = scorer.finish();
  EXPECT_EQ(s.scored_frames, 1);
  EXPECT_EQ(s.no_grid_cells, 2);
  EXPECT_EQ(s.unmatched_cells, 0);
  EXPECT_EQ(s.image.all.total(), 0);
}

TEST(ComputeTimes, NearestRankPercentiles) {
  std::vector<double> ms;
  for (int i = 10; i >= 1; --i) ms.push_back(10.0 * i);  // 100 .. 10, unsorted
  const ComputeTimes t = summarize_compute_ms(ms);
  EXPECT_EQ(t.frames, 10);
  EXPECT_DOUBLE_EQ(t.median, 50);
  EXPECT_DOUBLE_EQ(t.p90, 90);
  EXPECT_DOUBLE_EQ(t.max, 100);
  EXPECT_EQ(summarize_compute_ms({}).frames, 0);
}

// The tool on a log: the table, the JSON, and refusals that name the problem.
class LiveScoreTool : public ::testing::Test {
 protected:
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("live_score_" + std::to_string(::getpid()) + "_" +
                                                ::testing::UnitTest::GetInstance()->current_test_info()->name());
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }

  template <class Msg>
  static void write(logio::LogWriter& log, const char* channel, const Msg& m) {
    std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    log.write(channel, m.utime, buf.data(), buf.size());
  }
  // A log of one labelled and predicted frame (one TN cell) on these channels.
  static void write_one_frame_log(const std::string& path, const char* labels_channel,
                                  const char* predictions_channel) {
    logio::LogWriter log(path);
    write(log, labels_channel, labels_message(1, {{1.0f, 0.0f, kTN, kFree}}));
    write(log, predictions_channel, prediction_message(1, {{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}}));
    log.close();
  }
  // Runs the tool; its exit code, and stdout + stderr in `output`.
  int run(const std::string& args, std::string& output) const {
    const std::string out_file = (dir / "out.txt").string();
    const int status =
        std::system((std::string(IVOA_LIVE_SCORE_BIN) + " " + args + " > " + out_file + " 2>&1").c_str());
    std::stringstream text;
    text << std::ifstream(out_file).rdbuf();
    output = text.str();
    return WEXITSTATUS(status);
  }
};

TEST_F(LiveScoreTool, ScoresALogAndWritesJson) {
  const std::string log_path = (dir / "live.lcmlog").string();
  {
    logio::LogWriter log(log_path);
    for (int64_t t = 1; t <= 4; ++t) {
      write(log, "INTROSPECTION_LABELS", labels_message(t, {{1.0f, 0.0f, kFP, kObstacle}, {1.5f, 0.0f, kTN, kFree}}));
      write(log, "INTROSPECTION",
            prediction_message(
                t, {{1.0f, 0.0f, t == 4 ? kTN : kFP, 1, kObstacle, kFP, 1}, {1.5f, 0.0f, kTN, 1, kFree, kTN, 1}},
                10.0 * t));
    }
    log.close();
  }
  std::string out;
  ASSERT_EQ(run(log_path + " --json " + (dir / "score.json").string(), out), 0) << out;
  EXPECT_NE(out.find("frames: 4 labelled, 4 predicted, 4 both (scored)"), std::string::npos) << out;
  EXPECT_NE(out.find("median 20.0 ms, 90th percentile 40.0 ms, max 40.0 ms over 4 frames"), std::string::npos) << out;
  std::stringstream json;
  json << std::ifstream(dir / "score.json").rdbuf();
  // From the image alone FP is 3 of 4, TN 4 of 4: mean per-class 0.875.
  EXPECT_NE(json.str().find("\"image\": {\"all\": {\"cells\": 8, \"mean_per_class\": 0.875000"), std::string::npos)
      << json.str();
}

// A robot whose processes were started with renamed channels: its log is
// scored by naming them, and without the names it is refused by them.
TEST_F(LiveScoreTool, RenamedChannelsAreReadWhenNamed) {
  const std::string log_path = (dir / "renamed.lcmlog").string();
  write_one_frame_log(log_path, "ROBOT2_LABELS", "ROBOT2_INTROSPECTION");
  std::string out;
  EXPECT_EQ(run(log_path, out), 3);
  EXPECT_NE(out.find("no INTROSPECTION messages to score"), std::string::npos) << out;
  ASSERT_EQ(run(log_path + " --introspection-channel ROBOT2_INTROSPECTION --labels-channel ROBOT2_LABELS", out), 0)
      << out;
  EXPECT_NE(out.find("frames: 1 labelled, 1 predicted, 1 both (scored)"), std::string::npos) << out;
  EXPECT_EQ(run(log_path + " --introspection-channel ROBOT2_INTROSPECTION", out), 3);
  EXPECT_NE(out.find("no INTROSPECTION_LABELS messages to score"), std::string::npos) << out;
}

TEST_F(LiveScoreTool, ALogWithoutIntrospectionIsRefusedByName) {
  const std::string log_path = (dir / "labels_only.lcmlog").string();
  {
    logio::LogWriter log(log_path);
    write(log, "INTROSPECTION_LABELS", labels_message(1, {{1.0f, 0.0f, kTN, kFree}}));
    log.close();
  }
  std::string out;
  EXPECT_EQ(run(log_path, out), 3);
  EXPECT_NE(out.find("labels_only.lcmlog: no INTROSPECTION messages to score"), std::string::npos) << out;
}

// Frames that match but hold no cell to score printed n/a everywhere, exit 0.
TEST_F(LiveScoreTool, FramesWithNothingToScoreAreRefused) {
  for (const bool no_cells : {true, false}) {
    const std::string log_path = (dir / (no_cells ? "no_cells.lcmlog" : "no_queries.lcmlog")).string();
    {
      logio::LogWriter log(log_path);
      write(log, "INTROSPECTION_LABELS",
            labels_message(1, no_cells ? std::vector<Cell>{} : std::vector<Cell>{{1.0f, 0.0f, kTN, kFree}}));
      write(log, "INTROSPECTION",
            prediction_message(
                1, no_cells ? std::vector<Query>{{1.0f, 0.0f, kTN, 1, kFree, kTN, 1}} : std::vector<Query>{}));
      log.close();
    }
    std::string out;
    EXPECT_EQ(run(log_path, out), 3) << out;
    EXPECT_NE(out.find("no labelled cell has a prediction in the 1 frames with both (" +
                       std::string(no_cells ? "0" : "1") + " labelled cells"),
              std::string::npos)
        << out;
  }
}

// A log whose INTROSPECTION messages were all left out as unusable says so,
// not that ivoa-introspection was not running.
TEST_F(LiveScoreTool, MessagesAllLeftOutAreNotCalledMissing) {
  const std::string log_path = (dir / "bad_class.lcmlog").string();
  {
    logio::LogWriter log(log_path);
    write(log, "INTROSPECTION_LABELS", labels_message(1, {{1.0f, 0.0f, kTN, kFree}}));
    write(log, "INTROSPECTION", prediction_message(1, {{1.0f, 0.0f, 7, 1, kFree, kTN, 1}}));
    log.close();
  }
  std::string out;
  EXPECT_EQ(run(log_path, out), 3) << out;
  EXPECT_NE(out.find("no INTROSPECTION messages that could be used (1 left out as unusable or undecodable"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("was ivoa-introspection running"), std::string::npos) << out;
}

TEST_F(LiveScoreTool, ALogGivenTwiceIsRefusedRatherThanCountedTwice) {
  const std::string log_path = (dir / "live.lcmlog").string();
  write_one_frame_log(log_path, "INTROSPECTION_LABELS", "INTROSPECTION");
  std::string out;
  EXPECT_EQ(run(log_path + " " + (dir / "." / "live.lcmlog").string(), out), 2);
  EXPECT_NE(out.find("live.lcmlog is given twice: its frames would count twice"), std::string::npos) << out;
}

TEST_F(LiveScoreTool, AFileThatIsNotALogIsRefused) {
  std::ofstream(dir / "notes.txt") << "not an LCM log\n";
  std::string out;
  EXPECT_EQ(run((dir / "notes.txt").string(), out), 3);
  EXPECT_NE(out.find("notes.txt"), std::string::npos) << out;
}

}  // namespace
}  // namespace ivoa::tools
