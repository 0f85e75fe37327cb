// JPP's descriptor, window cost and point predicates on synthetic rectified
// pairs with a known disparity.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/stereo/daisy.hpp"
#include "ivoa/stereo/jpp_matcher.hpp"
#include "stereo_test_images.hpp"

namespace ivoa::stereo {
namespace {

const cv::Size kSize(480, 300);

TEST(Daisy, JppConfigurationHasThreeFloats) {
  DaisyDescriptors daisy(DaisyParams{});
  EXPECT_EQ(daisy.size(), 3);
  EXPECT_EQ(daisy.stride(), 4);
  EXPECT_EQ(DaisyDescriptors(DaisyParams{5.0, 3, 8, 8}).size(), (3 * 8 + 1) * 8);
}

TEST(Daisy, RisingRampGivesEqualUnitComponents) {
  cv::Mat ramp(kSize, CV_8U);
  for (int u = 0; u < ramp.cols; ++u) ramp.col(u).setTo(u / 3);
  DaisyDescriptors daisy(DaisyParams{});
  daisy.set_image(ramp);
  const uint8_t* d = daisy.at(200, 150);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(DaisyDescriptors::value(d, i), 1.0 / std::sqrt(3.0), 6e-3) << i;
  EXPECT_EQ(d[3], 0);  // padding
}

TEST(Daisy, OnlyThePositiveHorizontalGradientCounts) {
  cv::Mat falling(kSize, CV_8U), vertical(kSize, CV_8U);
  for (int u = 0; u < kSize.width; ++u) falling.col(u).setTo(255 - u / 3);
  for (int v = 0; v < kSize.height; ++v) vertical.row(v).setTo(v / 2);
  for (const cv::Mat& image : {falling, vertical}) {
    DaisyDescriptors daisy(DaisyParams{});
    daisy.set_image(image);
    const uint8_t* d = daisy.at(200, 150);
    EXPECT_EQ(d[0] + d[1] + d[2], 0);
  }
}

TEST(Daisy, SamplesLieAheadOnTheSameRow) {
  // A dark-to-bright step at column 100: a pixel 5 columns before it sees the
  // edge only in its outer ring sample; a pixel at the edge in its centre.
  cv::Mat step(kSize, CV_8U, cv::Scalar(40));
  step.colRange(100, kSize.width).setTo(200);
  DaisyDescriptors daisy(DaisyParams{});
  daisy.set_image(step);
  const uint8_t* before = daisy.at(95, 150);
  EXPECT_GT(before[2], before[1]);
  EXPECT_GT(before[1], before[0]);
  EXPECT_LT(DaisyDescriptors::value(before, 0), 0.05f);
  const uint8_t* at = daisy.at(100, 150);
  EXPECT_GT(at[0], at[1]);
  EXPECT_GT(at[1], at[2]);
  const uint8_t* after = daisy.at(110, 150);  // the edge is behind every sample
  EXPECT_EQ(after[0] + after[1] + after[2], 0);
  // Lazily: only the chunks of the row that were asked for.
  EXPECT_EQ(daisy.computed_count(), 2 * DaisyDescriptors::kChunk);
}

JppConfig jpp() { return JppConfig{}; }

// Share of window hypotheses at `offset` pixels from the true disparity 12
// that JPP confirms (CP), on a texture of blob size ~`blur`.
double confirmed_share(double blur, int offset) {
  const cv::Mat left = test::random_texture(kSize, 1, blur);
  JppMatcher matcher(jpp());
  matcher.set_images(left, test::shift_to_right_view(left, 12));
  int tested = 0, matched = 0;
  for (int v = 20; v < kSize.height - 20; v += 7) {
    for (int u = 40; u < kSize.width - 20; u += 7, ++tested)
      matched += matcher.confident_positive({u, v}, {u - 12 + offset, v}) == PointCheck::kMatch;
  }
  return static_cast<double>(matched) / tested;
}

TEST(JppMatcher, TrueDisparityMatchesAndWrongOnesDoNot) {
  const cv::Mat left = test::random_texture(kSize, 1, 2.0);
  JppMatcher matcher(jpp());
  matcher.set_images(left, test::shift_to_right_view(left, 12));
  EXPECT_LT(*matcher.cost({200, 150}, {188, 150}), 1e-6);
  EXPECT_EQ(confirmed_share(2.0, 0), 1.0);
  for (int offset : {-5, -4, 4, 5}) EXPECT_LT(confirmed_share(2.0, offset), 0.05) << offset;
}

TEST(JppMatcher, FineTextureIsAmbiguousForThisDescriptor) {
  // Characterisation of JPP's 3-float DAISY: the smoothed *positive part* of
  // the x-gradient is a local texture-energy field. For texture much finer
  // than its ~2 px smoothing it is nearly constant, so descriptors are all
  // ~(1,1,1)/sqrt(3) and far-off disparities match too. A real source of
  // missed obstacles for IVOA to learn, not a bug to fix here.
  EXPECT_EQ(confirmed_share(0.7, 0), 1.0);
  EXPECT_GT(confirmed_share(0.7, 15), 0.8);
  EXPECT_LT(confirmed_share(2.0, 15), 0.4);
}

TEST(JppMatcher, FractionalDisparityMatchesAtTheNearestPixel) {
  const cv::Mat left = test::random_texture(kSize, 2, 1.5);
  JppMatcher matcher(jpp());
  matcher.set_images(left, test::shift_to_right_view(left, 9.4));
  int tested = 0, matched = 0;
  for (int v = 20; v < kSize.height - 20; v += 9) {
    for (int u = 40; u < kSize.width - 20; u += 9) {
      ++tested;
      matched += matcher.confident_positive({u, v}, {u - 9, v}) == PointCheck::kMatch;
    }
  }
  EXPECT_GT(matched, 0.95 * tested);
}

TEST(JppMatcher, TexturelessRegionsMatchAnyDisparity) {
  // JPP's failure mode, kept on purpose: zero descriptors match anything,
  // so a texture-less obstacle reads as free ground.
  const cv::Mat flat(kSize, CV_8U, cv::Scalar(128));
  JppMatcher matcher(jpp());
  matcher.set_images(flat, flat);
  for (int d : {0, 5, 17, 40}) {
    EXPECT_EQ(*matcher.cost({200, 150}, {200 - d, 150}), 0.0);
    EXPECT_EQ(matcher.confident_positive({200, 150}, {200 - d, 150}), PointCheck::kMatch);
  }
}

TEST(JppMatcher, OptionalTextureGateWithholdsTexturelessVerdicts) {
  JppConfig config = jpp();
  config.texture_gate = 0.5;
  const cv::Mat flat(kSize, CV_8U, cv::Scalar(128));
  JppMatcher gated(config);
  gated.set_images(flat, flat);
  EXPECT_EQ(gated.confident_positive({200, 150}, {190, 150}), PointCheck::kUnobserved);
  const cv::Mat textured = test::random_texture(kSize, 3);
  gated.set_images(textured, textured);
  EXPECT_GT(gated.texture({200, 150}), 0.5);
  EXPECT_EQ(gated.confident_positive({200, 150}, {200, 150}), PointCheck::kMatch);
}

TEST(JppMatcher, BorderWindowsAreNotBiasedTowardsMatch) {
  // Unrelated images: every window is a mismatch. Dividing by the pixels
  // actually compared keeps a corner window's cost as high as an interior one
  // (JPP divides by 121, so a corner window looked 3x better).
  const cv::Mat left = test::random_texture(kSize, 4), right = test::random_texture(kSize, 5);
  JppConfig config = jpp();
  config.min_window_fraction = 0.2;
  JppMatcher matcher(config);
  matcher.set_images(left, right);
  double interior = 0;
  int n = 0;
  for (int v = 50; v < 250; v += 10, ++n) interior += *matcher.cost({240, v}, {240, v});
  interior /= n;
  const auto corner = matcher.cost({0, 0}, {0, 0});  // 6x6 of 11x11 inside
  ASSERT_TRUE(corner);
  EXPECT_GT(*corner, 0.6 * interior);
  EXPECT_GT(interior, config.conf_pos_thresh);
}

TEST(JppMatcher, WindowsMostlyOutsideTheImageGiveNoVerdict) {
  const cv::Mat left = test::random_texture(kSize, 6);
  JppMatcher matcher(jpp());  // min_window_fraction 0.5
  matcher.set_images(left, left);
  EXPECT_FALSE(matcher.cost({0, 0}, {0, 0}));       // 36 of 121 pixels inside
  EXPECT_TRUE(matcher.cost({3, 150}, {3, 150}));    // 99 of 121
  EXPECT_FALSE(matcher.cost({-1, 150}, {3, 150}));  // centre outside
  EXPECT_EQ(matcher.confident_positive({0, 0}, {0, 0}), PointCheck::kUnobserved);
  EXPECT_EQ(matcher.confident_positive({10, 150}, {500, 150}), PointCheck::kUnobserved);
}

TEST(JppMatcher, CacheDistinguishesHypothesesThroughOneLeftPixel) {
  // JPP keyed its cache on the left pixel alone: the second hypothesis below
  // would have reused the first's verdict.
  const cv::Mat left = test::random_texture(kSize, 7);
  JppMatcher matcher(jpp());
  matcher.set_images(left, test::shift_to_right_view(left, 10));
  EXPECT_EQ(matcher.confident_positive({200, 150}, {190, 150}), PointCheck::kMatch);
  EXPECT_EQ(matcher.confident_positive({200, 150}, {180, 150}), PointCheck::kNoMatch);
  EXPECT_EQ(matcher.confident_positive({200, 150}, {190, 150}), PointCheck::kMatch);
  EXPECT_EQ(matcher.stats().cp_tests, 3);
  EXPECT_EQ(matcher.stats().cp_cache_hits, 1);
}

TEST(JppMatcher, ConfidentNegativeNeedsAClearMismatch) {
  const cv::Mat left = test::random_texture(kSize, 8);
  JppMatcher matcher(jpp());
  matcher.set_images(left, test::shift_to_right_view(left, 10));
  EXPECT_FALSE(matcher.confident_negative({200, 150}, {190, 150}));
  const cv::Mat flat(kSize, CV_8U, cv::Scalar(90));
  matcher.set_images(flat, flat);
  EXPECT_FALSE(matcher.confident_negative({200, 150}, {150, 150}));
}

TEST(JppMatcher, RejectsMismatchedImageSizes) {
  JppMatcher matcher(jpp());
  EXPECT_THROW(matcher.set_images(cv::Mat(kSize, CV_8U), cv::Mat(cv::Size(100, 100), CV_8U)), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa::stereo
