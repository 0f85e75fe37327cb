#pragma once
// Training batches: raw dataset patches -> the network's normalised input,
// with the photometric changes a camera sees from frame to frame and rig to
// rig (exposure, contrast, gamma, white balance, sensor noise) applied on
// the way. No geometric flips: JPP's descriptor uses the positive
// horizontal gradient only, so a mirrored patch can fail differently.
//
// Everything but the noise is a per-sample, per-channel function of the
// 8-bit value, so it becomes a 256-entry table, and decoding, augmenting and
// normalising is one pass over the batch. As separate whole-batch tensor
// passes (to float, affine, clamp, pow, noise, normalise) it cost as much as
// the network's forward and backward on a CPU.
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include <torch/torch.h>

#include "ivoa/introspection/model.hpp"

namespace ivoa::introspection {

// Ranges the parameters are drawn from, uniformly. Factors are relative to
// the recorded image; values live on [0, 1] (8-bit / 255).
struct PhotometricRanges {
  std::array<double, 2> contrast{0.7, 1.3};       // around the patch mean
  std::array<double, 2> exposure{0.6, 1.4};       // overall gain
  std::array<double, 2> white_balance{0.9, 1.1};  // per colour channel gain
  std::array<double, 2> view_gain{0.95, 1.05};    // per view (the right sensor's sensitivity differs)
  std::array<double, 2> gamma{0.8, 1.25};
  std::array<double, 2> noise_sigma{0.0, 0.03};  // Gaussian sensor noise, per pixel
};

// One sample's draw. The views of a pair share exposure, contrast, white
// balance and gamma (one rig), each view with a small gain of its own.
struct PhotometricParams {
  double contrast = 1, exposure = 1, gamma = 1, noise_sigma = 0;
  std::array<double, 3> white_balance{1, 1, 1};  // RGB
  std::array<double, 2> view_gain{1, 1};
  int noise_index = 0;  // which field of the noise bank
};

class BatchAugmenter {
 public:
  // augment = false gives plain normalisation (what inference sees).
  BatchAugmenter(const ModelInfo& info, bool augment, uint64_t seed, PhotometricRanges ranges = {});

  // patches: B pointers to 8-bit BGR patches, views x S rows of S pixels
  // (the dataset layout) -> [B, 3 x views, S, S] float RGB, (x - mean) / std,
  // resized to info.input_size if it differs.
  torch::Tensor operator()(const std::vector<const uint8_t*>& patches);

  // The same with given parameters (one per patch): for tests.
  torch::Tensor apply(const std::vector<const uint8_t*>& patches, const std::vector<PhotometricParams>& params) const;

  PhotometricParams draw();

  static constexpr int kNoiseBankSize = 256;

 private:
  void fill_sample(const uint8_t* patch, const PhotometricParams& p, float* out) const;

  ModelInfo info_;
  bool augment_;
  PhotometricRanges ranges_;
  std::mt19937_64 rng_;
  int size_;                  // S
  std::vector<float> noise_;  // kNoiseBankSize fields of 3 x views x S x S unit normals
};

}  // namespace ivoa::introspection
