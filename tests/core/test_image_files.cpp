// Figures written whole, or a message that says which file and why not.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "file_size_limit.hpp"
#include "ivoa/core/image_files.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

cv::Mat noise_image() {
  cv::Mat image(120, 160, CV_8UC3);
  cv::randu(image, 0, 255);
  return image;
}

TEST(WriteImageFile, WritesTheFormatTheNameSays) {
  test::TempDir dir;
  std::string error;
  const cv::Mat image = noise_image();
  ASSERT_TRUE(write_image_file(dir.file("a.png"), image, error)) << error;
  EXPECT_EQ(cv::norm(cv::imread(dir.file("a.png")), image, cv::NORM_INF), 0);  // PNG: lossless
  ASSERT_TRUE(write_image_file(dir.file("a.jpg"), image, error)) << error;
  EXPECT_EQ(cv::imread(dir.file("a.jpg")).size(), image.size());
}

TEST(WriteImageFile, SaysWhyItCannot) {
  test::TempDir dir;
  std::string error;
  EXPECT_FALSE(write_image_file(dir.file("figure.txt"), noise_image(), error));
  EXPECT_EQ(error, dir.file("figure.txt") + ": no image format for the name (use .png or .jpg)");
  EXPECT_FALSE(write_image_file(dir.file("no/figure.png"), noise_image(), error));
  EXPECT_EQ(error, dir.file("no/figure.png") + ": there is no folder " + dir.file("no"));
  ASSERT_TRUE(write_image_file(dir.file("old.png"), noise_image(), error)) << error;
  const auto old_size = std::filesystem::file_size(dir.file("old.png"));
  {
    const test::FileSizeLimit nearly_full_disk(1000);
    EXPECT_FALSE(write_image_file(dir.file("old.png"), noise_image(), error));
  }
  EXPECT_NE(error.find(dir.file("old.png") + ": cannot write (File too large)"), std::string::npos) << error;
  EXPECT_EQ(std::filesystem::file_size(dir.file("old.png")), old_size);
}

}  // namespace
}  // namespace ivoa
