// The fully convolutional network equals patch-by-patch evaluation, and the
// batched MC-dropout head computes exactly T dropout forwards.
#include <ATen/CPUGeneratorImpl.h>
#include <gtest/gtest.h>

#include "mc_dropout.hpp"
#include "networks.hpp"

namespace ivoa::introspection {
namespace {

// Random BatchNorm statistics, so eval-mode BN is not the identity.
void randomize_batchnorm(torch::nn::Module& net) {
  torch::NoGradGuard no_grad;
  for (auto& m : net.modules(false))
    if (auto* bn = m->as<torch::nn::BatchNorm2d>()) {
      bn->running_mean.uniform_(-0.2, 0.2);
      bn->running_var.uniform_(0.5, 1.5);
      bn->weight.uniform_(0.5, 1.5);
      bn->bias.uniform_(-0.1, 0.1);
    }
}

TEST(SlideNet, WholeImagePassEqualsEveryPatchAlone) {
  torch::manual_seed(3);
  SlideNet net;
  randomize_batchnorm(*net);
  net->eval();
  torch::NoGradGuard no_grad;
  const auto image = torch::randn({1, 3, 260, 340});  // 9 rows x 13 cols of cells
  int64_t rows = 0, cols = 0;
  const auto cells = net->cell_features(image, rows, cols);
  ASSERT_EQ(rows, 9);
  ASSERT_EQ(cols, 13);
  ASSERT_EQ(cells.size(0), rows * cols);
  std::vector<torch::Tensor> patches;
  for (int64_t r = 0; r < rows; ++r)
    for (int64_t c = 0; c < cols; ++c)
      patches.push_back(image.index({0, torch::indexing::Slice(), torch::indexing::Slice(r * 20, r * 20 + 100),
                                     torch::indexing::Slice(c * 20, c * 20 + 100)}));
  const auto alone = net->features(torch::stack(patches));
  const double scale = alone.abs().max().item<double>();
  EXPECT_GT(scale, 0.1);
  EXPECT_LT((cells - alone).abs().max().item<double>(), 1e-4 * scale);
  // ...and so are the class probabilities of the deterministic head.
  const auto p_cells = torch::softmax(net->head(cells), -1), p_alone = torch::softmax(net->head(alone), -1);
  EXPECT_LT((p_cells - p_alone).abs().max().item<double>(), 1e-5);
}

// The channels-last trunk (the default, for speed) computes what NCHW does,
// forward on patches and whole images and backward, up to float rounding.
TEST(SlideNet, ChannelsLastComputesWhatNchwComputes) {
  torch::manual_seed(4);
  SlideNet net(0.5, 6);
  randomize_batchnorm(*net);
  const auto patches = torch::randn({8, 6, 100, 100}), image = torch::randn({1, 6, 180, 220});
  // Inference first for both layouts: a training-mode forward moves the
  // batch norms' running statistics.
  const auto infer = [&](bool channels_last) {
    net->channels_last = channels_last;
    net->eval();
    torch::NoGradGuard no_grad;
    int64_t rows = 0, cols = 0;
    return std::vector<torch::Tensor>{net->features(patches), net->cell_features(image, rows, cols)};
  };
  const auto conv1_gradient = [&](bool channels_last) {
    net->channels_last = channels_last;
    net->train();
    net->zero_grad();
    net->features(patches).square().sum().backward();
    return net->trunk[0]->as<torch::nn::Conv2d>()->weight.grad().clone();
  };
  auto nchw = infer(false), nhwc = infer(true);
  nchw.push_back(conv1_gradient(false));
  nhwc.push_back(conv1_gradient(true));
  for (size_t k = 0; k < nchw.size(); ++k) {
    ASSERT_EQ(nchw[k].sizes(), nhwc[k].sizes()) << k;
    const double scale = nchw[k].abs().max().item<double>();
    EXPECT_GT(scale, 0.01) << k;
    EXPECT_LT((nchw[k] - nhwc[k]).abs().max().item<double>(), 1e-4 * scale) << k;
  }
}

TEST(InferenceMaxPool, EqualsMaxPool2dExactly) {
  torch::manual_seed(7);
  const auto x = torch::randn({2, 5, 37, 52});
  for (const auto& [kernel, stride] : std::vector<std::pair<int64_t, int64_t>>{{2, 1}, {2, 2}, {3, 2}}) {
    InferenceMaxPool pool(kernel, stride);
    pool->eval();
    torch::NoGradGuard no_grad;
    const auto fast = pool(x), reference = torch::max_pool2d(x, kernel, stride);
    ASSERT_EQ(fast.sizes(), reference.sizes()) << kernel << "/" << stride;
    EXPECT_TRUE(torch::equal(fast, reference)) << kernel << "/" << stride;
  }
}

TEST(SlideNet, FullFrameGridIs26By44) {
  SlideNet net;
  net->eval();
  torch::NoGradGuard no_grad;
  int64_t rows = 0, cols = 0;
  const auto cells = net->cell_features(torch::zeros({1, 3, 600, 960}), rows, cols);
  EXPECT_EQ(rows, 26);
  EXPECT_EQ(cols, 44);
  EXPECT_EQ(cells.size(0), 26 * 44);
  EXPECT_EQ(cells.size(1), 256);
}

TEST(McDropout, EachPassIsADropoutForwardAndStatsAreRight) {
  torch::manual_seed(5);
  SlideNet net;
  net->eval();
  const auto features = torch::rand({37, 256});
  auto generator = at::detail::createCPUGenerator(11);
  const McStats s = mc_dropout_head(*net, features, 20, generator);
  ASSERT_EQ(s.passes.sizes(), (std::vector<int64_t>{20, 37, 4}));
  torch::NoGradGuard no_grad;
  for (int t = 0; t < 20; ++t) {
    // The plain forward of the network with this pass's masks.
    const auto h1 = torch::relu(net->fc1(features * s.fc1_masks[t]));
    const auto h2 = torch::relu(net->fc2(h1 * s.fc2_masks[t]));
    const auto expected = torch::softmax(net->fc3(h2), -1);
    EXPECT_LT((s.passes[t] - expected).abs().max().item<double>(), 1e-5) << "pass " << t;
  }
  // Passes differ: dropout is really on, about half the units kept.
  EXPECT_GT((s.passes[0] - s.passes[1]).abs().max().item<double>(), 1e-3);
  const double kept = (s.fc1_masks > 0).to(torch::kFloat).mean().item<double>();
  EXPECT_NEAR(kept, 0.5, 0.05);
  EXPECT_NEAR(s.fc1_masks.max().item<double>(), 2.0, 1e-6);  // inverted dropout scale 1/(1-p)
  // Mean and unbiased variance over passes, recomputed in double.
  const auto p = s.passes.to(torch::kDouble);
  const auto mean = p.sum(0) / 20.0;
  const auto var = (p - mean).pow(2).sum(0) / 19.0;
  EXPECT_LT((s.mean.to(torch::kDouble) - mean).abs().max().item<double>(), 1e-6);
  EXPECT_LT((s.variance.to(torch::kDouble) - var).abs().max().item<double>(), 1e-6);
  EXPECT_LT((s.mean.sum(1) - 1).abs().max().item<double>(), 1e-5);
  // Given the verdict: per pass P(FP | obstacle) and P(FN | free), then mean and variance.
  const auto fp_obstacle = p.select(2, 2) / (p.select(2, 0) + p.select(2, 2));
  const auto fn_free = p.select(2, 3) / (p.select(2, 1) + p.select(2, 3));
  const auto errors = torch::stack({fp_obstacle, fn_free}, -1);  // [T, N, 2]
  const auto e_mean = errors.sum(0) / 20.0;
  const auto e_var = (errors - e_mean).pow(2).sum(0) / 19.0;
  EXPECT_LT((s.verdict_mean.to(torch::kDouble) - e_mean).abs().max().item<double>(), 1e-5);
  EXPECT_LT((s.verdict_variance.to(torch::kDouble) - e_var).abs().max().item<double>(), 1e-5);
  // Not the ratio of the means: that is what "pass by pass" is about.
  const auto ratio_of_means = mean.select(1, 2) / (mean.select(1, 0) + mean.select(1, 2));
  EXPECT_GT((e_mean.select(1, 0) - ratio_of_means).abs().max().item<double>(), 1e-4);
}

TEST(McDropout, OnePassHasZeroVariance) {
  torch::manual_seed(6);
  SlideNet net;
  net->eval();
  const McStats s = deterministic_head(*net, torch::rand({5, 256}));
  EXPECT_EQ(s.variance.abs().max().item<double>(), 0.0);
  EXPECT_EQ(s.verdict_variance.abs().max().item<double>(), 0.0);
  const auto m = s.mean;
  const auto want = m.select(1, 3) / (m.select(1, 1) + m.select(1, 3));
  EXPECT_LT((s.verdict_mean.select(1, 1) - want).abs().max().item<double>(), 1e-6);
}

TEST(McDropout, SameSeedSamePassesOtherSeedOtherPasses) {
  SlideNet net;
  const auto features = torch::rand({5, 256});
  auto g1 = at::detail::createCPUGenerator(1), g2 = at::detail::createCPUGenerator(1),
       g3 = at::detail::createCPUGenerator(2);
  const auto a = mc_dropout_head(*net, features, 4, g1).passes;
  const auto b = mc_dropout_head(*net, features, 4, g2).passes;
  const auto c = mc_dropout_head(*net, features, 4, g3).passes;
  EXPECT_TRUE(torch::equal(a, b));
  EXPECT_FALSE(torch::equal(a, c));
}

TEST(AlexNet224, ReferenceShapes) {
  AlexNet224 net;
  net->eval();
  torch::NoGradGuard no_grad;
  const auto f = net->features(torch::zeros({2, 3, 224, 224}));
  EXPECT_EQ(f.size(1), 9216);
  EXPECT_EQ(net->fc1->weight.size(0), 2048);
  EXPECT_EQ(net->fc2->weight.size(0), 256);
  EXPECT_EQ(net->embedding(f).size(1), 256);
  EXPECT_EQ(net->head(f).size(1), 4);
}

}  // namespace
}  // namespace ivoa::introspection
