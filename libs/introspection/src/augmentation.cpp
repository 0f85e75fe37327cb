#include "augmentation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ivoa::introspection {
namespace {

// Mean of all values of a patch (every view and channel) on [0, 1]:
// contrast pivots around it.
double patch_mean(const uint8_t* patch, size_t values) {
  uint64_t sum = 0;
  for (size_t i = 0; i < values; ++i) sum += patch[i];
  return static_cast<double>(sum) / (255.0 * static_cast<double>(values));
}

}  // namespace

BatchAugmenter::BatchAugmenter(const ModelInfo& info, bool augment, uint64_t seed, PhotometricRanges ranges)
    : info_(info), augment_(augment), ranges_(ranges), rng_(seed), size_(info.patch_size) {
  if (size_ <= 0) throw std::invalid_argument("BatchAugmenter: the model info has no patch size");
  if (info_.views != 1 && info_.views != 2)
    throw std::invalid_argument("BatchAugmenter: views must be 1 or 2, not " + std::to_string(info_.views));
  if (!augment_) return;
  // A fixed bank of noise fields, drawn once: drawing fresh Gaussian noise
  // for every batch would cost more than the rest of the pass.
  noise_.resize(static_cast<size_t>(kNoiseBankSize) * 3 * static_cast<size_t>(info_.views * size_ * size_));
  std::normal_distribution<float> normal;
  for (auto& v : noise_) v = normal(rng_);
}

PhotometricParams BatchAugmenter::draw() {
  PhotometricParams p;
  if (!augment_) return p;
  const auto uniform = [this](const std::array<double, 2>& r) {
    return std::uniform_real_distribution<double>(r[0], r[1])(rng_);
  };
  p.contrast = uniform(ranges_.contrast);
  p.exposure = uniform(ranges_.exposure);
  for (auto& g : p.white_balance) g = uniform(ranges_.white_balance);
  for (auto& g : p.view_gain) g = uniform(ranges_.view_gain);
  p.gamma = uniform(ranges_.gamma);
  p.noise_sigma = uniform(ranges_.noise_sigma);
  p.noise_index = std::uniform_int_distribution<int>(0, kNoiseBankSize - 1)(rng_);
  return p;
}

torch::Tensor BatchAugmenter::operator()(const std::vector<const uint8_t*>& patches) {
  std::vector<PhotometricParams> params;
  params.reserve(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) params.push_back(draw());
  return apply(patches, params);
}

torch::Tensor BatchAugmenter::apply(const std::vector<const uint8_t*>& patches,
                                    const std::vector<PhotometricParams>& params) const {
  if (params.size() != patches.size()) throw std::invalid_argument("BatchAugmenter: one parameter set per patch");
  for (const auto& p : params)
    if (p.noise_sigma > 0 && (noise_.empty() || p.noise_index < 0 || p.noise_index >= kNoiseBankSize))
      throw std::invalid_argument(
          "BatchAugmenter: noise asked of an augmenter without a noise bank, or index out of range");
  const int64_t b = static_cast<int64_t>(patches.size()), channels = 3 * info_.views;
  auto out = torch::empty({b, channels, size_, size_}, torch::kFloat);
  const size_t sample_floats = static_cast<size_t>(channels) * size_ * size_;
  float* data = out.data_ptr<float>();
  at::parallel_for(0, b, 1, [&](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i)
      fill_sample(patches[static_cast<size_t>(i)], params[static_cast<size_t>(i)],
                  data + static_cast<size_t>(i) * sample_floats);
  });
  if (size_ == info_.input_size) return out;
  return torch::nn::functional::interpolate(out, torch::nn::functional::InterpolateFuncOptions()
                                                     .size(std::vector<int64_t>{info_.input_size, info_.input_size})
                                                     .mode(torch::kBilinear)
                                                     .align_corners(false));
}

// One patch: per view and RGB channel, a table from the 8-bit value to the
// augmented value on [0, 1] (contrast around the patch mean, exposure, white
// balance, view gain, clamp, gamma), then noise, clamp and normalisation.
void BatchAugmenter::fill_sample(const uint8_t* patch, const PhotometricParams& p, float* out) const {
  const size_t plane = static_cast<size_t>(size_) * size_;
  const double mean = p.contrast == 1 ? 0 : patch_mean(patch, plane * 3 * static_cast<size_t>(info_.views));
  std::array<float, 256> table{};
  for (int v = 0; v < info_.views; ++v)
    for (int c = 0; c < 3; ++c) {
      const double gain = p.exposure * p.white_balance[static_cast<size_t>(c)] * p.view_gain[static_cast<size_t>(v)];
      const double offset = mean * (1 - p.contrast) * gain;  // (x - mean) contrast + mean, times the gains
      for (int k = 0; k < 256; ++k) {
        const double y = std::clamp(k / 255.0 * p.contrast * gain + offset, 0.0, 1.0);
        table[static_cast<size_t>(k)] = static_cast<float>(p.gamma == 1 ? y : std::pow(y, p.gamma));
      }
      const auto m = static_cast<float>(info_.mean[static_cast<size_t>(c)]);
      const auto inv_std = static_cast<float>(1.0 / info_.std[static_cast<size_t>(c)]);
      const uint8_t* src = patch + static_cast<size_t>(v) * plane * 3 + static_cast<size_t>(2 - c);  // BGR -> RGB
      float* dst = out + static_cast<size_t>(3 * v + c) * plane;
      if (p.noise_sigma > 0) {
        const float sigma = static_cast<float>(p.noise_sigma);
        const float* noise =
            noise_.data() + (static_cast<size_t>(p.noise_index) * 3 * static_cast<size_t>(info_.views) +
                             static_cast<size_t>(3 * v + c)) *
                                plane;
        for (size_t q = 0; q < plane; ++q)
          dst[q] = (std::clamp(table[src[3 * q]] + sigma * noise[q], 0.0f, 1.0f) - m) * inv_std;
      } else {
        for (auto& t : table) t = (t - m) * inv_std;
        for (size_t q = 0; q < plane; ++q) dst[q] = table[src[3 * q]];
      }
    }
}

}  // namespace ivoa::introspection
