#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"

namespace ivoa {
namespace {

cv::Mat test_pattern() {
  cv::Mat img(60, 80, CV_8UC3);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c)
      img.at<cv::Vec3b>(r, c) = {static_cast<uint8_t>(c * 3), static_cast<uint8_t>(r * 4),
                                 static_cast<uint8_t>(200 - c)};
  return img;
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

TEST(ImageConvert, LosslessFormatsRoundTripExactly) {
  const cv::Mat bgr = test_pattern();
  for (int32_t f :
       std::vector<int32_t>{image_t::PIXEL_FORMAT_BGR, image_t::PIXEL_FORMAT_RGB, image_t::PIXEL_FORMAT_PNG}) {
    const image_t msg = encode_image(bgr, f, 1);
    EXPECT_EQ(msg.size, static_cast<int32_t>(msg.data.size()));
    EXPECT_EQ(max_abs_diff(decode_image(msg), bgr), 0) << pixelformat_name(f);
  }
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(max_abs_diff(decode_image(encode_image(gray, image_t::PIXEL_FORMAT_GRAY, 1), ColorOutput::kGray), gray), 0);
  EXPECT_EQ(max_abs_diff(decode_image(encode_image(bgr, image_t::PIXEL_FORMAT_GRAY, 1), ColorOutput::kGray), gray), 0);
}

TEST(ImageConvert, RgbWireOrderIsRgb) {
  cv::Mat bgr(1, 1, CV_8UC3, cv::Scalar(10, 20, 30));  // B=10 G=20 R=30
  const image_t msg = encode_image(bgr, image_t::PIXEL_FORMAT_RGB, 0);
  EXPECT_EQ(msg.data[0], 30);
  EXPECT_EQ(msg.data[2], 10);
}

TEST(ImageConvert, JpegIsClose) {
  const cv::Mat bgr = test_pattern();
  const cv::Mat back = decode_image(encode_image(bgr, image_t::PIXEL_FORMAT_JPEG, 1, 95));
  EXPECT_LT(cv::norm(back, bgr, cv::NORM_L1) / static_cast<double>(bgr.total() * 3), 3.0);
}

TEST(ImageConvert, BayerLayoutsDemosaicToTheRightColours) {
  // A flat colour must come back as that colour in the image interior for
  // every layout; swapped red/blue (the classic BayerRG mix-up) fails.
  const cv::Mat flat(40, 40, CV_8UC3, cv::Scalar(30, 120, 220));
  for (int32_t f : std::vector<int32_t>{image_t::PIXEL_FORMAT_BAYER_RGGB, image_t::PIXEL_FORMAT_BAYER_BGGR,
                                        image_t::PIXEL_FORMAT_BAYER_GBRG, image_t::PIXEL_FORMAT_BAYER_GRBG}) {
    const image_t msg = encode_image(flat, f, 0);
    EXPECT_EQ(msg.row_stride, 40);
    const cv::Mat back = decode_image(msg);
    const cv::Vec3b px = back.at<cv::Vec3b>(20, 20);
    EXPECT_NEAR(px[0], 30, 2) << pixelformat_name(f);
    EXPECT_NEAR(px[1], 120, 2) << pixelformat_name(f);
    EXPECT_NEAR(px[2], 220, 2) << pixelformat_name(f);
  }
  // GenICam BayerRG8: row 0 = R G R G.
  const cv::Mat raw = mosaic_bayer(flat, image_t::PIXEL_FORMAT_BAYER_RGGB);
  EXPECT_EQ(raw.at<uint8_t>(0, 0), 220);
  EXPECT_EQ(raw.at<uint8_t>(0, 1), 120);
  EXPECT_EQ(raw.at<uint8_t>(1, 1), 30);
}

TEST(ImageConvert, BadImagesSayWhatIsWrong) {
  image_t msg = encode_image(test_pattern(), image_t::PIXEL_FORMAT_BGR, 0);
  msg.data.resize(100);
  msg.size = 100;
  try {
    decode_image(msg);
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("needs 14400 bytes"), std::string::npos) << e.what();
  }
  msg = encode_image(test_pattern(), image_t::PIXEL_FORMAT_PNG, 0);
  msg.width = 10;
  EXPECT_THROW(decode_image(msg), ImageError);
  msg.pixelformat = 12345;
  EXPECT_THROW(decode_image(msg), ImageError);
  msg = encode_image(test_pattern(), image_t::PIXEL_FORMAT_JPEG, 0);
  for (size_t i = 10; i < msg.data.size(); ++i) msg.data[i] = 0;
  EXPECT_THROW(decode_image(msg), ImageError);
  // width * 3 wraps round int32 to 1: no longer passes for a 16-byte row (OpenCV aborted on it)
  msg = encode_image(test_pattern(), image_t::PIXEL_FORMAT_BGR, 0);
  msg.width = 715'827'883;
  msg.height = 2;
  msg.row_stride = 16;
  msg.data.assign(64, 0);
  msg.size = 64;
  try {
    decode_image(msg);
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("row_stride 16 is smaller than width * 3"), std::string::npos) << e.what();
  }
}

TEST(ImageConvert, DepthRoundTripsLittleEndian) {
  cv::Mat depth(3, 4, CV_16UC1);
  for (int i = 0; i < 12; ++i) depth.at<uint16_t>(i / 4, i % 4) = static_cast<uint16_t>(i * 1000 + 7);
  const depth_image_t msg = encode_depth(depth, 570, 571, 319.5, 239.5, 5);
  EXPECT_EQ(msg.data[2], (1007 & 0xff));
  EXPECT_EQ(msg.data[3], (1007 >> 8));
  EXPECT_EQ(cv::norm(decode_depth(msg), depth, cv::NORM_INF), 0);
  depth_image_t bad = msg;
  bad.width = 5;
  EXPECT_THROW(decode_depth(bad), ImageError);
  bad = msg;
  bad.format = 9;
  EXPECT_THROW(decode_depth(bad), ImageError);
}

}  // namespace
}  // namespace ivoa
