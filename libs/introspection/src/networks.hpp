#pragma once
// The networks (LibTorch; private to the library).
//
// Both end in the paper's head: dropout -> FC1 -> ReLU -> dropout -> FC2
// (256) -> ReLU -> FC3 (4). MC-dropout inference runs the trunk once and
// only the head T times (dropout exists only there).
//
// "slidenet" (default): AlexNet-shaped, 5 conv + 3 FC, built so the trunk
// run once over a whole image yields exactly the trunk outputs of every
// 100x100 patch at stride 20: every convolution is unpadded ("valid") and
// every stride divides the patch stride, so a patch at image offset 20k
// maps to offset 20k/s in each layer's output:
//   conv1 5x5/5 (patch 100 -> 20)   conv2 3x3 (18)   maxpool 2/2 (9)
//   conv3 3x3 (7)   conv4 3x3 (5)   conv5 3x3 (3)   maxpool 2/1 (2)
// FC1 then reads the 2x2x64 block of each cell: on a whole image it is a
// 2x2 convolution with stride 2 (the patch stride, 20, over the trunk's 10).
// FC1 is 128 wide (the paper fixes only FC2, the 256-d embedding): the T
// dropout passes recompute FC1 and FC2 for every cell, and at 256 that
// alone took longer than the 100 ms frame budget on two cores.
//
// "alexnet": the reference model (torchvision AlexNet trunk at 224x224,
// head 9216 -> 2048 -> 256 -> 4), for parity and for users with GPUs and
// pretrained weights. Patches are resized to 224 and run one by one.
#include <string>

#include <torch/torch.h>

namespace ivoa::introspection {

// Max pooling (unpadded, square window) that skips, at inference, the argmax
// indices at::max_pool2d computes even without autograd (LibTorch 1.13):
// on a whole frame they cost as much as two of the trunk's convolutions.
// The values are the same either way (a max is exact); training and
// gradient mode use at::max_pool2d.
class InferenceMaxPoolImpl : public torch::nn::Module {
 public:
  InferenceMaxPoolImpl(int64_t kernel, int64_t stride) : kernel_(kernel), stride_(stride) {}
  torch::Tensor forward(const torch::Tensor& x);

 private:
  int64_t kernel_, stride_;
};
TORCH_MODULE(InferenceMaxPool);

class IntrospectionNetImpl : public torch::nn::Module {
 public:
  IntrospectionNetImpl(int64_t features, int64_t fc1_width, double dropout);

  // Normalised patches [B, 3 x views, S, S] -> FC1 inputs [B, F].
  virtual torch::Tensor features(const torch::Tensor& patches) = 0;
  // Training/deterministic forward: logits [B, 4] (dropout per the module's mode).
  torch::Tensor forward(const torch::Tensor& patches) { return head(features(patches)); }
  torch::Tensor head(const torch::Tensor& features);
  // FC2 output after ReLU, no dropout: the 256-d embedding used for clustering.
  torch::Tensor embedding(const torch::Tensor& features);

  torch::nn::Linear fc1{nullptr}, fc2{nullptr}, fc3{nullptr};
  torch::nn::Dropout drop1{nullptr}, drop2{nullptr};
  double dropout_p;
};

class SlideNetImpl : public IntrospectionNetImpl {
 public:
  static constexpr int kPatch = 100, kStride = 20, kTrunkStride = 10, kFc1Width = 128;
  explicit SlideNetImpl(double dropout = 0.5, int64_t in_channels = 3);
  torch::Tensor features(const torch::Tensor& patches) override;
  // Normalised image [1, 3 x views, H, W] -> FC1 inputs of every cell [rows * cols, F],
  // row-major; rows/cols are set to the heatmap size.
  torch::Tensor cell_features(const torch::Tensor& image, int64_t& rows, int64_t& cols);
  torch::nn::Sequential trunk{nullptr};
  // Run the trunk channels-last (NHWC): oneDNN's convolutions and batch
  // norm are faster in that layout (a training step 1.33x on two cores,
  // docs/benchmarks.md), and the values differ from NCHW's only in float
  // rounding. false: PyTorch's default layout (the benchmark's baseline).
  bool channels_last = true;

 private:
  torch::Tensor trunk_input(const torch::Tensor& x) const;
};
TORCH_MODULE(SlideNet);

class AlexNet224Impl : public IntrospectionNetImpl {
 public:
  static constexpr int kInput = 224;
  explicit AlexNet224Impl(double dropout = 0.5, int64_t in_channels = 3);
  torch::Tensor features(const torch::Tensor& patches) override;
  torch::nn::Sequential trunk{nullptr};
};
TORCH_MODULE(AlexNet224);

// "slidenet" or "alexnet" for 1 or 2 views (3 or 6 input channels); throws
// std::invalid_argument otherwise.
std::shared_ptr<IntrospectionNetImpl> make_network(const std::string& architecture, double dropout, int views = 1);
int input_size_of(const std::string& architecture);

}  // namespace ivoa::introspection
