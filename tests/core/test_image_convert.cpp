#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/depth_image_t.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/stereo_image_t.hpp"

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

// A pair whose images were taken 5 s apart was matched as one view.
TEST(ImageConvert, StereoPairTimesMustAgree) {
  stereo_image_t pair{};
  pair.utime = pair.left.utime = pair.right.utime = 1'700'000'000'000'000;
  EXPECT_EQ(stereo_times_error(pair), "");
  pair.right.utime += kMaxStereoSkewUs;  // a 1 Hz rig's half period: still a pair
  EXPECT_EQ(stereo_times_error(pair), "");
  pair.right.utime = pair.left.utime + 5'000'000;
  EXPECT_EQ(stereo_times_error(pair), "its left and right images were taken 5000 ms apart");
  pair.right.utime = pair.left.utime;
  pair.utime += 7'000'000;
  EXPECT_EQ(stereo_times_error(pair), "its images' utimes lie 7000 ms from the pair's");
  pair.left.utime = pair.right.utime = 0;  // unknown: not compared
  EXPECT_EQ(stereo_times_error(pair), "");
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
  // width * 3 wraps round int32 to 1: OpenCV aborted on it; now over the pixel bound
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
    EXPECT_EQ(std::string(e.what()), "image size 715827883x2 is not between 1 and 67108864 pixels");
  }
}

std::string decode_error(const image_t& msg) {
  try {
    decode_image(msg);
  } catch (const ImageError& e) {
    return e.what();
  }
  return "decoded";
}

// A compressed image is decompressed only when its header's size is the
// message's, and that size is bounded: a 584 kB PNG of 1.8 GB of pixels
// used to be decompressed before its size was compared.
TEST(ImageConvert, ACompressedImageIsCheckedBeforeItIsDecompressed) {
  const cv::Mat big(2000, 3000, CV_8UC1, cv::Scalar(0));
  for (const int32_t format : std::vector<int32_t>{image_t::PIXEL_FORMAT_PNG, image_t::PIXEL_FORMAT_JPEG}) {
    image_t msg = encode_image(big, format, 0);
    msg.width = 80;
    msg.height = 60;
    const std::string name = format == image_t::PIXEL_FORMAT_PNG ? "PNG" : "JPEG";
    EXPECT_EQ(decode_error(msg), name + " header says 3000x2000 but the message says 80x60");
    msg.data.resize(3);
    msg.size = 3;
    EXPECT_EQ(decode_error(msg), name + " data has no readable " + name + " header");
  }
  // a header rewritten to 20000x20000, and the message saying so too
  image_t msg = encode_image(test_pattern(), image_t::PIXEL_FORMAT_PNG, 0);
  for (const size_t at : {16u, 20u}) {
    msg.data[at] = 0, msg.data[at + 1] = 0, msg.data[at + 2] = 0x4e, msg.data[at + 3] = 0x20;
  }
  msg.width = msg.height = 20000;
  EXPECT_EQ(decode_error(msg), "image size 20000x20000 is not between 1 and 67108864 pixels");
  msg.width = 0;
  EXPECT_EQ(decode_error(msg), "image size 0x20000 is not between 1 and 67108864 pixels");
  // a JPEG with application segments before its frame header still decodes
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", test_pattern(), jpeg);
  const std::vector<uint8_t> comment = {0xFF, 0xFE, 0x00, 0x06, 'i', 'v', 'o', 'a'};
  jpeg.insert(jpeg.begin() + 2, comment.begin(), comment.end());
  image_t commented = encode_image(test_pattern(), image_t::PIXEL_FORMAT_JPEG, 0);
  commented.data = jpeg;
  commented.size = static_cast<int32_t>(jpeg.size());
  EXPECT_EQ(decode_image(commented).size(), cv::Size(80, 60));
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
