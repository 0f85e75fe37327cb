// The shared figure pieces: distinct class colours, filled and hollow dots,
// captions that fit the width, heatmaps placed at patch centres and cut at
// the image border.
#include "ivoa/figures/paper_figure.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace ivoa::figures {
namespace {

cv::Vec3b bgr(const cv::Scalar& s) {
  return cv::Vec3b(static_cast<uint8_t>(s[0]), static_cast<uint8_t>(s[1]), static_cast<uint8_t>(s[2]));
}

TEST(Figures, TheFourClassesHaveDistinctColoursAndOthersAreGrey) {
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) EXPECT_NE(class_colour(a), class_colour(b)) << a << " vs " << b;
  EXPECT_EQ(class_colour(-1), class_colour(7));
  for (int k = 0; k < 4; ++k) EXPECT_NE(class_colour(k), class_colour(-1));
}

TEST(Figures, AnnouncedDotsAreFilledAndWithheldOnesOutlined) {
  cv::Mat image(60, 100, CV_8UC3, cv::Scalar(255, 255, 255));
  draw_dot(image, {25, 30}, 3, true);
  draw_dot(image, {75, 30}, 3, false);
  EXPECT_EQ(image.at<cv::Vec3b>(30, 25), bgr(class_colour(3)));
  EXPECT_EQ(image.at<cv::Vec3b>(30, 75), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(image.at<cv::Vec3b>(30, 75 + 8), bgr(class_colour(3)));
}

TEST(Figures, LongCaptionsAreSetSmallerToFitTheWidth) {
  cv::Mat image(120, 320, CV_8UC3, cv::Scalar(255, 255, 255));
  draw_caption(image, 0, kCaptionHeight, "a caption far too long for an image of three hundred and twenty pixels");
  cv::Mat bright, text;
  cv::inRange(image(cv::Rect(image.cols - 10, 0, 10, kCaptionHeight)), cv::Scalar(100, 100, 100),
              cv::Scalar(255, 255, 255), bright);
  EXPECT_EQ(cv::countNonZero(bright), 0) << "the text runs into the right margin";
  cv::inRange(image(cv::Rect(0, 0, image.cols, kCaptionHeight)), cv::Scalar(200, 200, 200), cv::Scalar(255, 255, 255),
              text);
  EXPECT_GT(cv::countNonZero(text), 100) << "no text was drawn";
  EXPECT_EQ(image.at<cv::Vec3b>(kCaptionHeight + 5, 5), cv::Vec3b(255, 255, 255)) << "the band ends at its height";
}

TEST(Figures, HeatmapValuesSitAtTheirPatchCentres) {
  const cv::Mat left(200, 200, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::Mat values(2, 2, CV_32F, cv::Scalar(0));
  values.at<float>(1, 1) = 1;  // the patch at (100, 100): its centre is (150, 150)
  const cv::Mat out = blend_heatmap(left, {2, 2, 100, 100}, values, 1.0, "");
  const cv::Vec3b high = out.at<cv::Vec3b>(170, 170), low = out.at<cv::Vec3b>(60, 60);
  EXPECT_GT(high[2], high[0]) << "the hot cell is red";
  EXPECT_GT(low[0], low[2]) << "the cold cell is blue";
}

TEST(Figures, AHeatmapReachingPastTheImageIsCutNotDropped) {
  // A grid wider than the image (a message for another image size must not
  // leave the panel blank or throw).
  const cv::Mat left(100, 100, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Mat values(4, 4, CV_32F, cv::Scalar(1));
  cv::Mat out;
  ASSERT_NO_THROW(out = blend_heatmap(left, {4, 4, 40, 100}, values, 1.0, ""));
  ASSERT_EQ(out.size(), left.size());
  EXPECT_GT(out.at<cv::Vec3b>(90, 90)[2], 50) << "the visible part is coloured";
}

}  // namespace
}  // namespace ivoa::figures
