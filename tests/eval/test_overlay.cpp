#include "overlay.hpp"

#include <gtest/gtest.h>

#include "ivoa/figures/paper_figure.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::tools {
namespace {

using introspection::Prediction;

constexpr int kTP = 0, kTN = 1, kFP = 2, kFN = 3;

// From the image alone: TN, confidently. Given the verdict: wrong if it
// said obstacle (P(FP | obstacle) = 0.8), right if it said free.
Prediction free_looking_cell(float verdict_variance) {
  Prediction p;
  p.predicted = kTN;
  p.probability = {0.02f, 0.90f, 0.07f, 0.01f};
  p.announced = true;
  p.verdict_error = {0.8f, 0.1f};
  p.verdict_error_variance = {verdict_variance, verdict_variance};
  return p;
}

LabelledCell cell_with_verdict(int stereo_state) {
  LabelledCell c;
  c.u = 40;
  c.v = 60;
  c.label = kTN;
  c.stereo_state = stereo_state;
  return c;
}

TEST(EvalOverlay, ImageAloneDotsIgnoreTheVerdict) {
  std::vector<LabelledCell> cells{cell_with_verdict(obstacle_grid_t::STATE_OBSTACLE)};
  set_predictions(cells, {free_looking_cell(0.001f)}, false, 0.01);
  EXPECT_EQ(cells[0].predicted, kTN);
  EXPECT_TRUE(cells[0].announced);
}

TEST(EvalOverlay, DotsGivenTheVerdictFollowTheRecordedState) {
  std::vector<LabelledCell> cells{cell_with_verdict(obstacle_grid_t::STATE_OBSTACLE),
                                  cell_with_verdict(obstacle_grid_t::STATE_FREE),
                                  cell_with_verdict(obstacle_grid_t::STATE_UNKNOWN), cell_with_verdict(-1)};
  const Prediction p = free_looking_cell(0.001f);
  set_predictions(cells, {p, p, p, p}, true, 0.01);
  EXPECT_EQ(cells[0].predicted, kFP);  // said obstacle, P(wrong) 0.8
  EXPECT_EQ(cells[1].predicted, kTN);  // said free, P(wrong) 0.1
  EXPECT_TRUE(cells[0].announced && cells[1].announced);
  EXPECT_EQ(cells[2].predicted, kTN);  // no verdict: the image alone
  EXPECT_EQ(cells[3].predicted, kTN);
}

TEST(EvalOverlay, VerdictGateWithholdsUncertainDots) {
  std::vector<LabelledCell> cells{cell_with_verdict(obstacle_grid_t::STATE_OBSTACLE)};
  set_predictions(cells, {free_looking_cell(0.05f)}, true, 0.01);
  EXPECT_EQ(cells[0].predicted, kFP);
  EXPECT_FALSE(cells[0].announced);
}

TEST(EvalOverlay, RefusesPredictionsThatDoNotMatchTheCells) {
  std::vector<LabelledCell> cells{cell_with_verdict(obstacle_grid_t::STATE_FREE)};
  EXPECT_THROW(set_predictions(cells, {}, true, 0.01), std::invalid_argument);
}

// A frame whose heatmaps are uniform: every class's probability 0.25, the
// given uncertainty everywhere.
introspection::Heatmaps uniform_heatmaps(float uncertainty) {
  introspection::Heatmaps h;
  h.rows = h.cols = 2;
  h.stride = h.patch_size = 100;
  for (auto& p : h.probability) p = cv::Mat(2, 2, CV_32F, cv::Scalar(0.25));
  h.uncertainty = cv::Mat(2, 2, CV_32F, cv::Scalar(uncertainty));
  return h;
}

// The uncertainty panel's colour at a patch centre below its title band.
cv::Vec3b uncertainty_colour(const introspection::Heatmaps& h, double uncertainty_max) {
  const cv::Mat left(200, 200, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Mat figure = compose_frame_figure(left, h, {}, false, uncertainty_max);
  return figure.at<cv::Vec3b>(150, 2 * left.cols + 150);
}

TEST(EvalOverlay, TheSharedScaleIsTheLargestValueAnyFrameShows) {
  const auto calm = uniform_heatmaps(0.02f), unsure = uniform_heatmaps(0.04f), sure = uniform_heatmaps(0.0f);
  EXPECT_DOUBLE_EQ(figures::uncertainty_scale_top({calm.uncertainty, unsure.uncertainty}), 0.04f);
  EXPECT_DOUBLE_EQ(figures::uncertainty_scale_top({sure.uncertainty}), figures::kMinUncertaintyScale)
      << "not stretched from 0";
  EXPECT_DOUBLE_EQ(figures::uncertainty_scale_top({}), figures::kMinUncertaintyScale);
}

TEST(EvalOverlay, ASharedUncertaintyScaleKeepsFramesComparable) {
  const auto calm = uniform_heatmaps(0.02f), unsure = uniform_heatmaps(0.04f);
  // Each frame on its own scale: both panels show their maximum, alike.
  EXPECT_EQ(uncertainty_colour(calm, 0), uncertainty_colour(unsure, 0));
  EXPECT_EQ(uncertainty_colour(unsure, 0), uncertainty_colour(unsure, 0.04)) << "its own scale is its maximum";
  // On one scale they differ, and a colour stands for one value: the calm
  // frame on 0.04 looks as the unsure one does on twice that.
  EXPECT_NE(uncertainty_colour(calm, 0.04), uncertainty_colour(unsure, 0.04));
  EXPECT_EQ(uncertainty_colour(calm, 0.04), uncertainty_colour(unsure, 0.08));
}

TEST(EvalOverlay, DrawsFilledAndHollowDotsInTheClassColour) {
  const cv::Mat image(160, 200, CV_8UC3, cv::Scalar(255, 255, 255));
  LabelledCell filled = cell_with_verdict(obstacle_grid_t::STATE_OBSTACLE);
  filled.v = 120;  // below the caption and legend bands
  filled.label = -1;
  filled.predicted = kFP;
  LabelledCell hollow = filled;
  hollow.u = 150;
  hollow.announced = false;
  const cv::Mat out = draw_grid(image, {filled, hollow}, true);
  const cv::Scalar fp = figures::class_colour(kFP);
  EXPECT_EQ(out.at<cv::Vec3b>(120, 40), cv::Vec3b(fp[0], fp[1], fp[2]));
  EXPECT_EQ(out.at<cv::Vec3b>(120, 150), cv::Vec3b(255, 255, 255));  // hollow: the image shows through
  EXPECT_EQ(out.at<cv::Vec3b>(120, 150 + 8), cv::Vec3b(fp[0], fp[1], fp[2]));
}

}  // namespace
}  // namespace ivoa::tools
