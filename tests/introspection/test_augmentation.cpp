// Training batches: without augmentation they are exactly what inference
// sees; with it, every value follows the photometric model written out
// plainly here, and the draws stay in their ranges.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "augmentation.hpp"
#include "tensors.hpp"

namespace ivoa::introspection {
namespace {

constexpr int kSize = 100;

ModelInfo two_view_info() {
  ModelInfo info;
  info.patch_size = kSize;
  info.input_size = kSize;
  info.views = 2;
  return info;
}

// Random 8-bit BGR patches, views x S rows of S pixels, as the dataset stores them.
std::vector<std::vector<uint8_t>> random_patches(int count, int views, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::vector<uint8_t>> out(static_cast<size_t>(count));
  for (auto& p : out) {
    p.resize(static_cast<size_t>(views) * kSize * kSize * 3);
    for (auto& v : p) v = static_cast<uint8_t>(byte(rng));
  }
  return out;
}

std::vector<const uint8_t*> pointers(const std::vector<std::vector<uint8_t>>& patches) {
  std::vector<const uint8_t*> out;
  for (const auto& p : patches) out.push_back(p.data());
  return out;
}

// The photometric model, value by value: contrast around the patch mean,
// gains, clamp, gamma, then normalisation (no noise).
float expected_value(const std::vector<uint8_t>& patch, const PhotometricParams& p, const ModelInfo& info, int view,
                     int rgb, int y, int x) {
  double mean = 0;
  for (uint8_t v : patch) mean += v / 255.0;
  mean /= static_cast<double>(patch.size());
  const uint8_t raw = patch[((static_cast<size_t>(view) * kSize + y) * kSize + x) * 3 + (2 - rgb)];
  const double gain = p.exposure * p.white_balance[static_cast<size_t>(rgb)] * p.view_gain[static_cast<size_t>(view)];
  const double v = std::pow(std::clamp(((raw / 255.0 - mean) * p.contrast + mean) * gain, 0.0, 1.0), p.gamma);
  return static_cast<float>((v - info.mean[static_cast<size_t>(rgb)]) / info.std[static_cast<size_t>(rgb)]);
}

TEST(BatchAugmenter, WithoutAugmentationIsTheInferenceNormalisation) {
  const ModelInfo info = two_view_info();
  const auto patches = random_patches(5, 2, 1);
  auto raw = torch::empty({5, 2 * kSize, kSize, 3}, torch::kUInt8);
  for (int i = 0; i < 5; ++i)
    std::memcpy(raw[i].data_ptr<uint8_t>(), patches[static_cast<size_t>(i)].data(), patches[0].size());
  BatchAugmenter plain(info, false, 7);
  const auto batch = plain(pointers(patches));
  ASSERT_EQ(batch.sizes(), (std::vector<int64_t>{5, 6, kSize, kSize}));
  EXPECT_LT((batch - normalize_patches(raw, info)).abs().max().item<double>(), 1e-5);
}

// Inference's patch path (a table lookup per value) gives the whole-batch
// tensor passes' floats bit for bit, so evaluation and the near cells see
// what they always saw; with a resize to 224 too.
TEST(PatchesToTensor, EqualsTheTensorPassesBitForBit) {
  for (const int input_size : {kSize, 224}) {
    ModelInfo info = two_view_info();
    info.input_size = input_size;
    const auto patches = random_patches(3, 2, 4);
    auto raw = torch::empty({3, 2 * kSize, kSize, 3}, torch::kUInt8);
    std::vector<cv::Mat> mats;
    for (int i = 0; i < 3; ++i) {
      std::memcpy(raw[i].data_ptr<uint8_t>(), patches[static_cast<size_t>(i)].data(), patches[0].size());
      mats.push_back(cv::Mat(2 * kSize, kSize, CV_8UC3, const_cast<uint8_t*>(patches[static_cast<size_t>(i)].data())));
    }
    const auto looked_up = patches_to_tensor(mats, info);
    ASSERT_EQ(looked_up.sizes(), (std::vector<int64_t>{3, 6, input_size, input_size}));
    EXPECT_TRUE(torch::equal(looked_up, normalize_patches(raw, info))) << "input size " << input_size;
  }
}

TEST(BatchAugmenter, EveryValueFollowsThePhotometricModel) {
  const ModelInfo info = two_view_info();
  const auto patches = random_patches(2, 2, 2);
  PhotometricParams a;
  a.contrast = 1.25, a.exposure = 0.7, a.gamma = 0.85, a.white_balance = {0.92, 1.0, 1.08}, a.view_gain = {1.0, 0.96};
  PhotometricParams b;
  b.contrast = 0.75, b.exposure = 1.35, b.gamma = 1.2, b.white_balance = {1.05, 0.95, 1.0}, b.view_gain = {1.04, 1.0};
  const BatchAugmenter augmenter(info, true, 3);
  const auto batch = augmenter.apply(pointers(patches), {a, b});
  const auto values = batch.accessor<float, 4>();
  const std::array<PhotometricParams, 2> params{a, b};
  int clamped = 0;
  for (int i = 0; i < 2; ++i)
    for (int view = 0; view < 2; ++view)
      for (int rgb = 0; rgb < 3; ++rgb)
        for (int y = 0; y < kSize; y += 7)
          for (int x = 0; x < kSize; x += 5) {
            const float want =
                expected_value(patches[static_cast<size_t>(i)], params[static_cast<size_t>(i)], info, view, rgb, y, x);
            ASSERT_NEAR(values[i][3 * view + rgb][y][x], want, 1e-5)
                << "sample " << i << " view " << view << " rgb " << rgb;
            clamped += want == static_cast<float>((1.0 - info.mean[static_cast<size_t>(rgb)]) /
                                                  info.std[static_cast<size_t>(rgb)]);
          }
  EXPECT_GT(clamped, 0);  // the strong gain of sample b saturates some values: the clamp was exercised
}

TEST(BatchAugmenter, NoiseHasTheDrawnStrengthAndStaysInRange) {
  const ModelInfo info = two_view_info();
  const auto patches = random_patches(1, 2, 3);
  const BatchAugmenter augmenter(info, true, 4);
  PhotometricParams quiet, noisy;
  noisy.noise_sigma = 0.02;
  noisy.noise_index = 17;
  const auto diff = (augmenter.apply(pointers(patches), {noisy}) - augmenter.apply(pointers(patches), {quiet}))[0][1];
  // Green channel, away from the clamp: (noise on [0, 1]) / std.
  const double sigma = diff.std().item<double>() * info.std[1];
  EXPECT_NEAR(sigma, 0.02, 0.002);
  const auto unit = augmenter.apply(pointers(patches), {noisy})[0][1] * info.std[1] + info.mean[1];
  EXPECT_GE(unit.min().item<double>(), -1e-6);
  EXPECT_LE(unit.max().item<double>(), 1 + 1e-6);
}

TEST(BatchAugmenter, DrawsStayInTheirRangesAndFollowTheSeed) {
  const ModelInfo info = two_view_info();
  const PhotometricRanges r;
  BatchAugmenter one(info, true, 5), same(info, true, 5), other(info, true, 6);
  bool differs = false;
  for (int k = 0; k < 200; ++k) {
    const PhotometricParams p = one.draw(), q = same.draw(), o = other.draw();
    EXPECT_EQ(p.gamma, q.gamma);
    EXPECT_EQ(p.noise_index, q.noise_index);
    differs = differs || p.gamma != o.gamma;
    EXPECT_GE(p.contrast, r.contrast[0]);
    EXPECT_LE(p.contrast, r.contrast[1]);
    EXPECT_GE(p.gamma, r.gamma[0]);
    EXPECT_LE(p.gamma, r.gamma[1]);
    EXPECT_LE(p.noise_sigma, r.noise_sigma[1]);
    for (double g : p.view_gain) EXPECT_NEAR(g, 1.0, 0.05 + 1e-12);
    EXPECT_GE(p.noise_index, 0);
    EXPECT_LT(p.noise_index, BatchAugmenter::kNoiseBankSize);
  }
  EXPECT_TRUE(differs);
  // Ranges of its own: no noise (ivoa-train --augment-noise 0), the gains still drawn.
  PhotometricRanges quiet;
  quiet.noise_sigma = {0.0, 0.0};
  BatchAugmenter without_noise(info, true, 5, quiet);
  bool gains_vary = false;
  for (int k = 0; k < 50; ++k) {
    const PhotometricParams p = without_noise.draw();
    EXPECT_EQ(p.noise_sigma, 0);
    gains_vary = gains_vary || p.exposure != 1;
  }
  EXPECT_TRUE(gains_vary);
  // Without augmentation the draw is the identity.
  BatchAugmenter plain(info, false, 5);
  const PhotometricParams id = plain.draw();
  EXPECT_EQ(id.contrast, 1);
  EXPECT_EQ(id.noise_sigma, 0);
}

TEST(BatchAugmenter, ResizesToTheNetworkInputAndRejectsNoiseWithoutABank) {
  ModelInfo info = two_view_info();
  info.views = 1;
  info.input_size = 224;  // alexnet
  const auto patches = random_patches(3, 1, 4);
  BatchAugmenter augmenter(info, true, 8);
  EXPECT_EQ(augmenter(pointers(patches)).sizes(), (std::vector<int64_t>{3, 3, 224, 224}));
  const BatchAugmenter plain(info, false, 8);
  PhotometricParams noisy;
  noisy.noise_sigma = 0.01;
  EXPECT_THROW(plain.apply(pointers(patches), {noisy}), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa::introspection
