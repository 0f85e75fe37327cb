#include "mc_dropout.hpp"

namespace ivoa::introspection {
namespace {

// Above this many elements (T * F * H1) FC1's masked weights are not materialised.
constexpr int64_t kMaxMaskedWeights = 16 * 1024 * 1024;

// [T, in] keep-masks scaled by 1/(1-p), as inverted dropout does in training.
torch::Tensor sample_masks(int passes, int64_t width, double p, torch::Generator& generator,
                           const torch::TensorOptions& options) {
  // Drawn on the CPU (small) so one generator serves any device.
  const auto keep = torch::rand({passes, width}, generator, torch::kFloat) >= p;
  return (keep.to(torch::kFloat) * static_cast<float>(1.0 / (1.0 - p))).to(options.device());
}

torch::Tensor variance_over_passes(const torch::Tensor& x) {
  return x.size(0) > 1 ? x.var(0, /*unbiased=*/true) : torch::zeros_like(x[0]);
}

}  // namespace

torch::Tensor verdict_errors(const torch::Tensor& probs) {
  const auto tp = probs.select(-1, 0), tn = probs.select(-1, 1), fp = probs.select(-1, 2), fn = probs.select(-1, 3);
  // Softmax outputs are never both zero in exact arithmetic; the floor only
  // guards against underflow.
  return torch::stack({fp / (tp + fp).clamp_min(1e-30), fn / (tn + fn).clamp_min(1e-30)}, -1);
}

McStats summarise_passes(const torch::Tensor& passes) {
  McStats s;
  s.passes = passes;
  s.mean = passes.mean(0);
  s.variance = variance_over_passes(passes);
  const auto errors = verdict_errors(passes);
  s.verdict_mean = errors.mean(0);
  s.verdict_variance = variance_over_passes(errors);
  return s;
}

McStats mc_dropout_head(IntrospectionNetImpl& net, const torch::Tensor& features, int passes,
                        torch::Generator& generator) {
  torch::NoGradGuard no_grad;
  const double p = net.dropout_p;
  const auto options = features.options();
  const int64_t n = features.size(0), f = features.size(1);
  const auto& w1 = net.fc1->weight;  // [H1, F]
  const int64_t h1 = w1.size(0);
  const auto m1 = sample_masks(passes, f, p, generator, options);  // [T, F]
  torch::Tensor h;                                                 // [N, T * H1], column t * H1 + j = unit j of pass t
  if (passes * f * h1 <= kMaxMaskedWeights) {
    // FC1 with input dropout for all passes in one product:
    // x (m_t * W1) for t = 1..T  ==  x [m_1 W1 | ... | m_T W1].
    const auto w1_all = (w1.unsqueeze(0) * m1.unsqueeze(1)).reshape({passes * h1, f});
    h = torch::addmm(net.fc1->bias.repeat({passes}), features, w1_all.t());
  } else {
    // A wide head (AlexNet's 9216 x 2048): T masked weight copies would not
    // fit in memory, so mask the inputs pass by pass.
    std::vector<torch::Tensor> per_pass;
    for (int t = 0; t < passes; ++t) per_pass.push_back(torch::addmm(net.fc1->bias, features * m1[t], w1.t()));
    h = torch::cat(per_pass, 1);
  }
  h.relu_();
  // Dropout before FC2, then FC2 for all (cell, pass) rows in one product.
  const auto m2 = sample_masks(passes, h1, p, generator, options);  // [T, H1]
  h.mul_(m2.reshape({1, passes * h1}));
  auto h2 = torch::addmm(net.fc2->bias, h.view({n * passes, h1}), net.fc2->weight.t());  // [N * T, 256]
  h2.relu_();
  const auto probs = torch::softmax(torch::addmm(net.fc3->bias, h2, net.fc3->weight.t()), -1)
                         .view({n, passes, 4})
                         .permute({1, 0, 2});  // [T, N, 4]
  McStats s = summarise_passes(probs);
  s.fc1_masks = m1;
  s.fc2_masks = m2;
  return s;
}

McStats deterministic_head(IntrospectionNetImpl& net, const torch::Tensor& features) {
  torch::NoGradGuard no_grad;
  const auto probs = torch::softmax(net.fc3(torch::relu(net.fc2(torch::relu(net.fc1(features))))), -1);
  return summarise_passes(probs.unsqueeze(0));
}

}  // namespace ivoa::introspection
