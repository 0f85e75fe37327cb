// Frames -> stereo_image_t, and buffers that must never yield pixels.
#include <arv.h>
#include <gtest/gtest.h>

#include "ivoa/aravis_stereo/aravis_buffer.hpp"
#include "ivoa/aravis_stereo/stereo_message.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::aravis_stereo {
namespace {

TEST(AravisBuffer, IncompleteBufferGivesNoPixelsAndSaysWhy) {
  ArvBuffer* buffer = arv_buffer_new_allocate(320 * 240);  // never filled: status "cleared"
  const FrameResult result = buffer_to_frame(buffer, Side::kRight);
  g_object_unref(buffer);
  EXPECT_FALSE(result.complete);
  EXPECT_TRUE(result.frame.data.empty());
  EXPECT_NE(result.problem.find("cleared"), std::string::npos) << result.problem;
}

StereoPair bayer_pair() {
  StereoPair pair;
  for (CameraFrame* f : {&pair.left, &pair.right}) {
    f->width = 8;
    f->height = 8;
    f->pixelformat = image_t::PIXEL_FORMAT_BAYER_RGGB;
    // R G R G ... / G B G B ...: what a sensor records of a red surface.
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) f->data.push_back(y % 2 == 0 ? (x % 2 == 0 ? 200 : 10) : (x % 2 == 0 ? 10 : 30));
  }
  pair.left.utime = 1000;
  pair.right.utime = 1003;
  return pair;
}

TEST(StereoMessage, RawPairKeepsBayerAndLeftTime) {
  const stereo_image_t msg = make_stereo_message(bayer_pair(), OutputFormat::kRaw, 7, "aravis");
  EXPECT_EQ(msg.utime, 1000);
  EXPECT_EQ(msg.seq, 7);
  EXPECT_EQ(msg.source, "aravis");
  EXPECT_EQ(msg.left.pixelformat, image_t::PIXEL_FORMAT_BAYER_RGGB);
  EXPECT_EQ(msg.left.row_stride, 8);
  EXPECT_EQ(msg.right.utime, 1003);
  EXPECT_EQ(msg.right.size, 64);
}

TEST(StereoMessage, BgrOutputIsDemosaicedWithRedWhereTheSensorSawRed) {
  const stereo_image_t msg = make_stereo_message(bayer_pair(), OutputFormat::kBgr, 0, "aravis");
  ASSERT_EQ(msg.left.pixelformat, image_t::PIXEL_FORMAT_BGR);
  ASSERT_EQ(msg.left.row_stride, 24);
  const cv::Mat bgr = decode_image(msg.left);
  const cv::Vec3b p = bgr.at<cv::Vec3b>(4, 4);
  EXPECT_EQ(p[2], 200) << "red";
  EXPECT_EQ(p[0], 30) << "blue";
  const stereo_image_t gray = make_stereo_message(bayer_pair(), OutputFormat::kGray, 0, "aravis");
  EXPECT_EQ(gray.right.pixelformat, image_t::PIXEL_FORMAT_GRAY);
  EXPECT_EQ(gray.right.size, 64);
}

TEST(StereoMessage, FrameWithWrongDataSizeIsRefused) {
  CameraFrame f;
  f.width = 4;
  f.height = 2;
  f.pixelformat = image_t::PIXEL_FORMAT_GRAY;
  f.data.assign(7, 0);
  EXPECT_THROW(frame_to_image(f, OutputFormat::kRaw), ImageError);
}

TEST(StereoMessage, OutputFormatNames) {
  EXPECT_EQ(parse_output_format("raw"), OutputFormat::kRaw);
  EXPECT_EQ(parse_output_format("bgr"), OutputFormat::kBgr);
  EXPECT_EQ(parse_output_format("gray"), OutputFormat::kGray);
  EXPECT_FALSE(parse_output_format("rgb"));
}

}  // namespace
}  // namespace ivoa::aravis_stereo
