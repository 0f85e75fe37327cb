// The simulated hardware's scenes: what the fake cameras and the synthetic
// depth sensor serve, and what the integration tests compare against.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/sim_hardware/frame_stamp.hpp"
#include "ivoa/sim_hardware/stereo_scene.hpp"
#include "ivoa/sim_hardware/synth_depth_scene.hpp"

namespace ivoa::sim_hardware {
namespace {

TEST(FrameStamp, RoundTripsThroughBayerMosaicAndDemosaic) {
  for (const FrameStamp stamp :
       {FrameStamp{0, false}, FrameStamp{1, true}, FrameStamp{0x2BCDEF, false}, FrameStamp{0x7FFFFF, true}}) {
    cv::Mat image(64, 320, CV_8UC3, cv::Scalar(10, 200, 90));
    write_stamp(image, stamp);
    cv::Mat demosaiced;
    cv::cvtColor(mosaic_bayer(image, image_t::PIXEL_FORMAT_BAYER_RGGB), demosaiced, cv::COLOR_BayerBG2BGR);
    ASSERT_EQ(read_stamp(demosaiced), stamp);
    cv::Mat gray;
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(read_stamp(gray), stamp);
  }
}

TEST(FrameStamp, KeepsTheLow23BitsOfTheTick) {
  cv::Mat image(8, 256, CV_8UC1, cv::Scalar(0));
  write_stamp(image, {0x1234567u, false});
  EXPECT_EQ(read_stamp(image)->tick, 0x234567u);
}

TEST(FrameStamp, RejectsImagesWithoutAValidStamp) {
  cv::Mat plain(64, 320, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_FALSE(read_stamp(plain));  // all-black blocks fail the check byte
  cv::Mat stamped = plain.clone();
  write_stamp(stamped, {4242, false});
  stamped(cv::Rect(8 * 20, 0, 8, 8)).setTo(cv::Scalar::all(255 - stamped.at<cv::Vec3b>(4, 8 * 20 + 4)[0]));
  EXPECT_FALSE(read_stamp(stamped)) << "a flipped bit must be detected";
  cv::Mat small(8, 100, CV_8UC1, cv::Scalar(0));
  EXPECT_FALSE(read_stamp(small));
}

TEST(StereoScene, RightViewIsTheLeftShiftedByTheDisparity) {
  PatternOptions pattern;
  pattern.disparity_px = 16;
  const StereoScene scene(pattern, /*stamp=*/false);
  const cv::Size size(320, 120);
  const cv::Mat left = scene.render(RigCamera::kLeft, {77, false}, size);
  const cv::Mat right = scene.render(RigCamera::kRight, {77, false}, size);
  // right(x) = left(x + 16)
  EXPECT_EQ(cv::norm(right(cv::Rect(0, 0, 304, 120)), left(cv::Rect(16, 0, 304, 120)), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(right, left, cv::NORM_L1), 0.0);
}

TEST(StereoScene, MovesWithTheTickAndIsDeterministic) {
  PatternOptions pattern;
  pattern.speed_px = 2;
  const StereoScene scene(pattern, /*stamp=*/true);
  const cv::Size size(320, 120);
  const cv::Mat a = scene.render(RigCamera::kLeft, {10, false}, size);
  EXPECT_EQ(cv::norm(a, scene.render(RigCamera::kLeft, {10, false}, size), cv::NORM_INF), 0.0);
  const cv::Mat b = scene.render(RigCamera::kLeft, {11, false}, size);
  EXPECT_EQ(cv::norm(b(cv::Rect(0, 20, 318, 100)), a(cv::Rect(2, 20, 318, 100)), cv::NORM_INF), 0.0);
  EXPECT_EQ(read_stamp(a)->tick, 10u);
  EXPECT_EQ(read_stamp(b)->tick, 11u);
}

TEST(StereoScene, FlatColourMaskAvoidsSquareEdgesAndTheStamp) {
  PatternOptions pattern;
  pattern.cell_px = 12;
  const StereoScene scene(pattern, true);
  const cv::Mat mask = scene.flat_colour_mask(RigCamera::kRight, 5, {320, 120});
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(0, 0, 320, 10))), 0);
  const double fraction = cv::countNonZero(mask) / (320.0 * 120.0);
  EXPECT_GT(fraction, 0.25);
  EXPECT_LT(fraction, 0.5);  // (8/12)^2 = 0.44 of each square
}

TEST(StereoScene, MissingImageFileIsNamed) {
  try {
    StereoScene scene({"/nonexistent/left.png"}, {"/nonexistent/right.png"});
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/left.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(StereoScene({"a.png"}, {}), std::invalid_argument);
}

TEST(SynthDepthScene, BoxAtOneMetreOnAWallAtTwoMovesOnePixelPerFrame) {
  namespace sd = synth_depth;
  std::vector<uint16_t> depth(sd::kWidth * sd::kHeight);
  for (const int64_t frame : {1, 2, 399, 400}) {
    sd::render_depth(frame, false, depth.data(), sd::kWidth);
    const sd::PixelRect box = sd::box_at(frame, false);
    EXPECT_EQ(box.x, sd::kBoxStartX + frame % sd::kBoxTravel);
    EXPECT_EQ(depth[box.y * sd::kWidth + box.x], sd::kBoxMm);
    EXPECT_EQ(depth[box.y * sd::kWidth + box.x - 1], sd::kWallMm);
    EXPECT_EQ(depth[(box.y + box.height - 1) * sd::kWidth + box.x + box.width - 1], sd::kBoxMm);
    EXPECT_EQ(depth[(box.y + box.height) * sd::kWidth + box.x], sd::kWallMm);
    EXPECT_EQ(depth[0], sd::kWallMm);
  }
}

TEST(SynthDepthScene, RegistrationShiftsTheBoxAndInvalidatesTheBorder) {
  namespace sd = synth_depth;
  std::vector<uint16_t> depth(sd::kWidth * sd::kHeight);
  sd::render_depth(5, true, depth.data(), sd::kWidth);
  const sd::PixelRect box = sd::box_at(5, true);
  EXPECT_EQ(box.x, sd::box_at(5, false).x + sd::kRegistrationShiftPx);
  EXPECT_EQ(depth[100 * sd::kWidth + sd::kRegistrationShiftPx - 1], 0);
  EXPECT_EQ(depth[100 * sd::kWidth + sd::kRegistrationShiftPx], sd::kWallMm);
  EXPECT_EQ(depth[box.y * sd::kWidth + box.x], sd::kBoxMm);
}

}  // namespace
}  // namespace ivoa::sim_hardware
