#pragma once
// Monte-Carlo dropout through the head only. Each pass samples one dropout
// mask per layer and applies it to every cell of the frame: a pass is one
// sample of the thinned network (dropout as weight sampling), the whole
// frame goes through it, and all T passes become one large matrix product
// instead of T * cells small ones. Per cell, the mean and the variance over
// the T passes are proper MC estimates; passes are independent draws.
#include <torch/torch.h>

#include "networks.hpp"

namespace ivoa::introspection {

struct McStats {
  torch::Tensor mean;      // [N, 4] mean softmax probability over passes
  torch::Tensor variance;  // [N, 4] variance over passes (unbiased, n - 1; 0 for one pass)
  torch::Tensor passes;    // [T, N, 4] every pass's probabilities
  // [N, 2] mean and variance over passes of the verdict errors
  // (verdict_errors()), each taken pass by pass.
  torch::Tensor verdict_mean, verdict_variance;
  torch::Tensor fc1_masks, fc2_masks;  // [T, F], [T, H1]: the dropout masks used (scaled keep masks)
};

// Per pass, the probability that the detector's verdict is wrong given what
// it said: [..., 0] = P(FP | obstacle) = p_FP / (p_TP + p_FP),
// [..., 1] = P(FN | free) = p_FN / (p_TN + p_FN). probs [..., 4] -> [..., 2].
torch::Tensor verdict_errors(const torch::Tensor& probs);

// Mean, variance and verdict statistics of the passes [T, N, 4].
McStats summarise_passes(const torch::Tensor& passes);

// features [N, F] (FC1 inputs); passes >= 2.
McStats mc_dropout_head(IntrospectionNetImpl& net, const torch::Tensor& features, int passes,
                        torch::Generator& generator);

// Deterministic head (no dropout), for passes <= 1.
McStats deterministic_head(IntrospectionNetImpl& net, const torch::Tensor& features);

}  // namespace ivoa::introspection
