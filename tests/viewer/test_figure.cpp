// The viewer's figure: ring and dot colours where the cells are, rings
// from labels, from Algorithm 1 on two grids, or from one grid's verdicts;
// heatmaps placed by patch geometry; missing parts said so; figure size.
#include <gtest/gtest.h>

#include "ivoa/figures/paper_figure.hpp"
#include "ivoa/viewer/figure.hpp"
#include "viewer_messages.hpp"

namespace ivoa::viewer {
namespace {

using figures::class_colour;

using namespace test;

cv::Mat background() { return cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(90, 90, 90)); }

FigureOptions full_size() {
  FigureOptions o;
  o.scale = 1.0;
  return o;
}

// True if the pixel is within `tolerance` of `colour` in every channel.
::testing::AssertionResult has_colour(const cv::Mat& image, int x, int y, const cv::Scalar& colour,
                                      int tolerance = 12) {
  const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
  for (int c = 0; c < 3; ++c)
    if (std::abs(p[c] - colour[c]) > tolerance)
      return ::testing::AssertionFailure() << "pixel (" << x << ", " << y << ") is " << p << ", expected " << colour;
  return ::testing::AssertionSuccess();
}

// A pixel on cell i's ring (radius 15, 4 px thick).
cv::Point on_ring(int i) { return {static_cast<int>(kCellU[i]) + 15, static_cast<int>(kCellV[i])}; }

TEST(ViewerFigure, RingsShowLabelsAndDotsShowPredictions) {
  FrameSet f;
  f.utime = 100;
  f.labels = labels(100, {0, 1, 2, 3});
  f.introspection = introspection(100, {3, 2, 1, 0});  // cells 0 and 2 announced, 1 and 3 withheld
  const cv::Mat fig = draw_frame_figure(background(), f, full_size());
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(has_colour(fig, on_ring(i).x, on_ring(i).y, class_colour(i))) << "cell " << i;
  const cv::Point c0(static_cast<int>(kCellU[0]), static_cast<int>(kCellV[0]));
  EXPECT_TRUE(has_colour(fig, c0.x, c0.y, class_colour(3))) << "announced: a filled FN dot";
  const cv::Point c1(static_cast<int>(kCellU[1]), static_cast<int>(kCellV[1]));
  EXPECT_TRUE(has_colour(fig, c1.x, c1.y, cv::Scalar(90, 90, 90))) << "withheld: hollow";
  EXPECT_TRUE(has_colour(fig, c1.x + 8, c1.y, class_colour(2))) << "withheld: its outline";
}

TEST(ViewerFigure, DotsCanShowThePredictionGivenTheVerdict) {
  FrameSet f;
  f.utime = 100;
  f.labels = labels(100, {0, 1, 2, 3});
  f.introspection = introspection(100, {3, 2, 1, 0});
  auto& h = *f.introspection;
  h.query_verdict = {obstacle_grid_t::STATE_OBSTACLE, obstacle_grid_t::STATE_FREE, obstacle_grid_t::STATE_OBSTACLE,
                     obstacle_grid_t::STATE_UNKNOWN};
  h.query_verdict_class = {introspection_labels_t::LABEL_TP, introspection_labels_t::LABEL_TN,
                           introspection_labels_t::LABEL_FP, introspection_labels_t::LABEL_NONE};
  h.query_verdict_announced = {1, 1, 0, 0};
  const auto marks = prediction_marks(f, true);
  ASSERT_EQ(marks.size(), 4u);
  EXPECT_EQ(marks[0].predicted, 0);
  EXPECT_EQ(marks[1].predicted, 1);
  EXPECT_TRUE(marks[1].announced);
  EXPECT_EQ(marks[2].predicted, 2);
  EXPECT_FALSE(marks[2].announced);
  EXPECT_EQ(marks[3].predicted, 0) << "verdict unknown: the image-alone prediction";
  EXPECT_EQ(prediction_marks(f, false)[0].predicted, 3) << "default: the image-alone prediction";
  FigureOptions options = full_size();
  options.dots_given_verdict = true;
  const cv::Mat fig = draw_frame_figure(background(), f, options);
  const cv::Point c0(static_cast<int>(kCellU[0]), static_cast<int>(kCellV[0]));
  EXPECT_TRUE(has_colour(fig, c0.x, c0.y, class_colour(0))) << "announced: a filled TP dot";
}

TEST(ViewerFigure, WithoutLabelsTheTwoGridsAreLabelledByAlgorithm1) {
  FrameSet f;
  f.utime = 100;
  // stereo: obstacle, free, free, obstacle; depth: free, free, obstacle, obstacle
  f.stereo = grid(100, {1, 0, 0, 1});
  f.depth = grid(100, {0, 0, 1, 1}, "depth_monitor");
  const auto marks = cell_marks(f);
  ASSERT_EQ(marks.size(), 4u);
  const int expected[] = {introspection_labels_t::LABEL_FP, introspection_labels_t::LABEL_TN,
                          introspection_labels_t::LABEL_FN, introspection_labels_t::LABEL_TP};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(marks[static_cast<size_t>(i)].ring_label, expected[i]) << "cell " << i;
  const cv::Mat fig = draw_frame_figure(background(), f, full_size());
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(has_colour(fig, on_ring(i).x, on_ring(i).y, class_colour(expected[i])));
}

TEST(ViewerFigure, WithOnlyTheStereoGridRingsShowItsVerdicts) {
  FrameSet f;
  f.utime = 100;
  f.stereo = grid(100, {0, 1, 2, 1});
  f.stereo->in_image[3] = 0;  // its patch leaves the image: not drawn
  const auto marks = cell_marks(f);
  ASSERT_EQ(marks.size(), 3u);
  EXPECT_EQ(marks[1].ring_verdict, obstacle_grid_t::STATE_OBSTACLE);
  const cv::Mat fig = draw_frame_figure(background(), f, full_size());
  EXPECT_TRUE(has_colour(fig, on_ring(0).x, on_ring(0).y, verdict_colour(obstacle_grid_t::STATE_FREE)));
  EXPECT_TRUE(has_colour(fig, on_ring(1).x, on_ring(1).y, verdict_colour(obstacle_grid_t::STATE_OBSTACLE)));
  EXPECT_TRUE(has_colour(fig, on_ring(3).x, on_ring(3).y, cv::Scalar(90, 90, 90)));
}

TEST(ViewerFigure, HeatmapsFollowThePatchGeometry) {
  FrameSet f;
  f.utime = 100;
  f.introspection = introspection(100);  // P(FP) = 1 in the left half, 0 in the right
  const cv::Mat fig = draw_frame_figure(background(), f, full_size());
  ASSERT_EQ(fig.size(), cv::Size(3 * kWidth, kHeight));
  const cv::Vec3b left = fig.at<cv::Vec3b>(120, kWidth + 60), right = fig.at<cv::Vec3b>(120, kWidth + 260);
  EXPECT_GT(left[2], left[0] + 40) << "high failure probability is red: " << left;
  EXPECT_GT(right[0], right[2] + 40) << "low failure probability is blue: " << right;
  // Uncertainty rises left to right: the right end is the hot end.
  const cv::Vec3b u_left = fig.at<cv::Vec3b>(120, 2 * kWidth + 20), u_right = fig.at<cv::Vec3b>(120, 3 * kWidth - 20);
  EXPECT_GT(u_left[0], u_left[2]);
  EXPECT_GT(u_right[2], u_right[0]);
}

TEST(ViewerFigure, AFixedUncertaintyScaleCoolsAFrameBelowIt) {
  FrameSet f;
  f.utime = 100;
  f.introspection = introspection(100);
  FigureOptions fixed = full_size();
  const cv::Vec3b own = draw_frame_figure(background(), f, fixed).at<cv::Vec3b>(120, 3 * kWidth - 20);
  fixed.uncertainty_max = 100.0;  // far above anything in the frame: its hottest cell is cold
  const cv::Vec3b scaled = draw_frame_figure(background(), f, fixed).at<cv::Vec3b>(120, 3 * kWidth - 20);
  EXPECT_GT(own[2], own[0]) << "on its own scale the frame's maximum is red";
  EXPECT_GT(scaled[0], scaled[2] + 40) << "far under a fixed maximum it is blue: " << scaled;
}

TEST(ViewerFigure, MissingIntrospectionLeavesDimPanelsAndTheFigureSizeStays) {
  FrameSet f;
  f.utime = 100;
  f.stereo = grid(100, {0, 0, 0, 0});
  FigureOptions half;
  half.scale = 0.5;
  EXPECT_EQ(draw_frame_figure(background(), f, half).size(), cv::Size(3 * kWidth / 2, kHeight / 2));
  const cv::Mat fig = draw_frame_figure(background(), f, full_size());
  EXPECT_TRUE(has_colour(fig, kWidth + 300, kHeight - 10, cv::Scalar(22, 22, 22), 3)) << "dimmed image";
  // A heatmap for another image size is not drawn either.
  f.introspection = introspection(100);
  f.introspection->image_width = 640;
  const cv::Mat other = draw_frame_figure(background(), f, full_size());
  EXPECT_TRUE(has_colour(other, kWidth + 300, kHeight - 10, cv::Scalar(22, 22, 22), 3));
}

TEST(ViewerFigure, UndrawableIntrospectionIsNamed) {
  introspection_t h = introspection(1);
  EXPECT_EQ(check_introspection(h), "");
  h.num_cells -= 1;
  EXPECT_EQ(check_introspection(h), "heatmap 10x16 but 159 cells");
  h = introspection(1);
  h.stride = 0;
  EXPECT_EQ(check_introspection(h), "heatmap geometry 10x16, stride 0, patch 20 is not drawable");
  h = introspection(1);
  h.patch_size = 100'000;  // OpenCV aborted the viewer drawing it
  EXPECT_EQ(check_introspection(h).rfind("heatmap of 10x16 patches of 100000 px every ", 0), 0u)
      << check_introspection(h);
  EXPECT_NE(check_introspection(h).find("more than its "), std::string::npos);
  h = introspection(1);
  h.rows = h.cols = h.num_cells = 1;
  h.stride = 100'000;  // one cell passed with any stride, and drawing it asked 30 GB
  EXPECT_EQ(check_introspection(h).rfind("heatmap of 1x1 patches of 20 px every 100000 px", 0), 0u)
      << check_introspection(h);
}

}  // namespace
}  // namespace ivoa::viewer
