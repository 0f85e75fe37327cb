// The stereo evaluation tool's pieces: disparity files, and the point-check
// scores on the real Middlebury "Aloe" pair (Debian's opencv-doc).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "disparity_io.hpp"
#include "point_check_scoring.hpp"
#include "stereo_test_images.hpp"
#include "test_rig.hpp"

namespace ivoa::stereo_eval {
namespace {

const std::string kAloe = "/usr/share/doc/opencv-doc/examples/data/";

TEST(DisparityIo, PfmRoundTripKeepsValuesAndMarksUnknown) {
  test::TempDir dir;
  cv::Mat d(4, 5, CV_32F);
  for (int i = 0; i < 20; ++i) d.at<float>(i) = 0.5f * static_cast<float>(i);
  d.at<float>(1, 1) = std::numeric_limits<float>::infinity();
  write_pfm(dir.file("d.pfm"), d);
  const cv::Mat raw = read_pfm(dir.file("d.pfm"));
  EXPECT_EQ(raw.at<float>(3, 4), 9.5f);  // rows come back top first
  const cv::Mat loaded = load_disparity(dir.file("d.pfm"));
  EXPECT_TRUE(std::isnan(loaded.at<float>(0, 0)));  // 0 = unknown
  EXPECT_TRUE(std::isnan(loaded.at<float>(1, 1)));  // inf = unknown
  EXPECT_EQ(loaded.at<float>(2, 3), 6.5f);
}

TEST(DisparityIo, APfmHeaderLargerThanItsDataIsRefusedBeforeAllocating) {
  test::TempDir dir;
  std::ofstream(dir.file("huge.pfm"), std::ios::binary) << "Pf\n99999999 99999999\n-1.0\n" << std::string(64, '\0');
  try {
    read_pfm(dir.file("huge.pfm"));
    FAIL() << "read a 99999999x99999999 PFM of 64 bytes";
  } catch (const DisparityFileError& e) {
    EXPECT_NE(std::string(e.what()).find("huge.pfm: its header says 99999999x99999999 but the file holds 64 bytes"),
              std::string::npos)
        << e.what();
  }
}

TEST(DisparityIo, PngValuesAreDividedAndZeroIsUnknown) {
  test::TempDir dir;
  cv::Mat png(2, 2, CV_16U, cv::Scalar(0));
  png.at<uint16_t>(0, 1) = 256 * 10 + 128;
  ASSERT_TRUE(cv::imwrite(dir.file("kitti.png"), png));
  const cv::Mat d = load_disparity(dir.file("kitti.png"), 256.0);
  EXPECT_FLOAT_EQ(d.at<float>(0, 1), 10.5f);
  EXPECT_TRUE(std::isnan(d.at<float>(1, 1)));
  EXPECT_THROW(load_disparity(dir.file("missing.png")), DisparityFileError);
  const cv::Mat half = scale_disparity(d, 0.5);
  EXPECT_EQ(half.size(), cv::Size(1, 1));
}

TEST(DisparityIo, AJpegCutShortIsRefusedNamingTheFile) {
  test::TempDir dir;
  cv::Mat texture(240, 320, CV_8U);
  cv::randu(texture, 0, 255);
  ASSERT_TRUE(cv::imwrite(dir.file("whole.jpg"), texture));
  EXPECT_EQ(read_image(dir.file("whole.jpg"), cv::IMREAD_GRAYSCALE).size(), texture.size());
  const auto size = std::filesystem::file_size(dir.file("whole.jpg"));
  std::filesystem::copy_file(dir.file("whole.jpg"), dir.file("trailer.jpg"));
  std::ofstream(dir.file("trailer.jpg"), std::ios::app | std::ios::binary) << std::string(4096, '\x5A');
  EXPECT_EQ(read_image(dir.file("trailer.jpg"), cv::IMREAD_GRAYSCALE).size(), texture.size())
      << "data a phone appends after the end of the image";
  std::filesystem::copy_file(dir.file("whole.jpg"), dir.file("cut.jpg"));
  std::filesystem::resize_file(dir.file("cut.jpg"), size / 2);
  try {
    read_image(dir.file("cut.jpg"), cv::IMREAD_GRAYSCALE);
    FAIL() << "decoded half a JPEG";
  } catch (const DisparityFileError& e) {
    EXPECT_EQ(std::string(e.what()), dir.file("cut.jpg") + ": a JPEG cut short (no end-of-image marker)");
  }
}

TEST(PointCheckScoring, SyntheticShiftScoresTruthAboveWrong) {
  const cv::Mat left = test::random_texture({320, 200}, 3, 2.0);
  const cv::Mat right = test::shift_to_right_view(left, 10);
  const cv::Mat truth(left.size(), CV_32F, cv::Scalar(10));
  ScoringOptions options;
  options.wrong_offsets = {5};
  JppPointModel jpp(stereo::JppConfig{});
  const ModelScore s = score(jpp, left, right, truth, options);
  EXPECT_GT(s.textured.pixels, 1000);
  EXPECT_EQ(s.textured.at_truth.value(), 1.0);
  EXPECT_LT(s.textured.wrong.value(), 0.05);
  EXPECT_GT(s.textured.truth_cheaper.value(), 0.99);
  // A blank pair is all "untextured", and JPP confirms every hypothesis there.
  const cv::Mat blank(left.size(), CV_8U, cv::Scalar(100));
  const ModelScore b = score(jpp, blank, blank, truth, options);
  EXPECT_EQ(b.textured.pixels, 0);
  EXPECT_EQ(b.untextured.wrong.value(), 1.0);
}

class Aloe : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kAloe + "aloeGT.png"))
      GTEST_SKIP() << "opencv-doc is not installed (no " << kAloe << "aloeGT.png)";
    for (const char* name : {"aloeL.jpg", "aloeR.jpg"}) {
      cv::Mat full = cv::imread(kAloe + name, cv::IMREAD_GRAYSCALE), half;
      cv::resize(full, half, cv::Size(641, 555), 0, 0, cv::INTER_AREA);
      (left_.empty() ? left_ : right_) = half;
    }
    truth_ = scale_disparity(load_disparity(kAloe + "aloeGT.png"), 0.5);
    ASSERT_EQ(truth_.size(), left_.size());
    options_.stride = 3;
  }
  cv::Mat left_, right_, truth_;
  ScoringOptions options_;
};

TEST_F(Aloe, JppCostPrefersTheTrueDisparity) {
  JppPointModel jpp(stereo::JppConfig{});
  const TextureClassScore s = score(jpp, left_, right_, truth_, options_).textured;
  EXPECT_GT(s.pixels, 20000);
  // Measured 90% / 70% (wrong = truth +-2, 4, 8 px): JPP's threshold 0.75
  // is lenient for its 3-float descriptor, but its cost ranks the truth
  // first in ~92% of cases (mean cost 0.29 vs 0.68).
  EXPECT_GT(s.at_truth.value(), 0.85);
  EXPECT_LT(s.wrong.value(), 0.8);
  EXPECT_GT(s.at_truth.value() - s.wrong.value(), 0.1);
  EXPECT_GT(s.truth_cheaper.value(), 0.85);
  EXPECT_LT(2.0 * s.mean_cost_truth(), s.mean_cost_wrong());
  EXPECT_LT(s.by_offset.at(4).value(), 0.75);
}

TEST_F(Aloe, SgbmIsAccurateWhereDense) {
  stereo::SgbmConfig config;
  config.num_disparities = 112;
  SgbmPointModel sgbm(config, 1.0);
  const TextureClassScore s = score(sgbm, left_, right_, truth_, options_).textured;
  EXPECT_GT(s.at_truth.value(), 0.6);
  EXPECT_LT(s.wrong.value(), 0.02);
}

}  // namespace
}  // namespace ivoa::stereo_eval
