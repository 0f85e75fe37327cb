#include "networks.hpp"

#include <stdexcept>

namespace ivoa::introspection {
namespace nn = torch::nn;
namespace {

nn::Sequential conv_bn_relu(nn::Sequential seq, int64_t in, int64_t out, int64_t k, int64_t stride = 1) {
  seq->push_back(nn::Conv2d(nn::Conv2dOptions(in, out, k).stride(stride).bias(false)));
  seq->push_back(nn::BatchNorm2d(out));
  seq->push_back(nn::ReLU(nn::ReLUOptions(true)));
  return seq;
}

}  // namespace

torch::Tensor InferenceMaxPoolImpl::forward(const torch::Tensor& x) {
  if (is_training() || torch::GradMode::is_enabled()) return torch::max_pool2d(x, kernel_, stride_);
  const int64_t rows = (x.size(2) - kernel_) / stride_ + 1, cols = (x.size(3) - kernel_) / stride_ + 1;
  // The window's element (dy, dx) of every output pixel, as one strided view.
  const auto tap = [&](int64_t dy, int64_t dx) {
    return x.slice(2, dy, dy + (rows - 1) * stride_ + 1, stride_).slice(3, dx, dx + (cols - 1) * stride_ + 1, stride_);
  };
  // Running maximum over the window's taps, in place after the first pair
  // (copying a strided view costs more than comparing two).
  torch::Tensor out;
  for (int64_t k = 1; k < kernel_ * kernel_; ++k) {
    const auto next = tap(k / kernel_, k % kernel_);
    out = out.defined() ? torch::maximum_out(out, out, next) : torch::maximum(tap(0, 0), next);
  }
  return out;
}

IntrospectionNetImpl::IntrospectionNetImpl(int64_t features, int64_t fc1_width, double dropout) : dropout_p(dropout) {
  drop1 = register_module("drop1", nn::Dropout(dropout));
  fc1 = register_module("fc1", nn::Linear(features, fc1_width));
  drop2 = register_module("drop2", nn::Dropout(dropout));
  fc2 = register_module("fc2", nn::Linear(fc1_width, 256));
  fc3 = register_module("fc3", nn::Linear(256, 4));
}

torch::Tensor IntrospectionNetImpl::head(const torch::Tensor& f) {
  auto h = torch::relu(fc1(drop1(f)));
  h = torch::relu(fc2(drop2(h)));
  return fc3(h);
}

torch::Tensor IntrospectionNetImpl::embedding(const torch::Tensor& f) { return torch::relu(fc2(torch::relu(fc1(f)))); }

SlideNetImpl::SlideNetImpl(double dropout, int64_t in_channels) : IntrospectionNetImpl(64 * 2 * 2, kFc1Width, dropout) {
  nn::Sequential t;
  t = conv_bn_relu(t, in_channels, 32, 5, 5);
  t = conv_bn_relu(t, 32, 64, 3);
  t->push_back(InferenceMaxPool(2, 2));
  t = conv_bn_relu(t, 64, 96, 3);
  t = conv_bn_relu(t, 96, 96, 3);
  t = conv_bn_relu(t, 96, 64, 3);
  t->push_back(InferenceMaxPool(2, 1));
  trunk = register_module("trunk", t);
}

torch::Tensor SlideNetImpl::trunk_input(const torch::Tensor& x) const {
  return channels_last ? x.contiguous(at::MemoryFormat::ChannelsLast) : x;
}

torch::Tensor SlideNetImpl::features(const torch::Tensor& patches) {
  // flatten() reads in logical (channel-major) order whatever the layout.
  return trunk->forward(trunk_input(patches)).flatten(1);  // [B, 64, 2, 2] -> [B, 256]
}

torch::Tensor SlideNetImpl::cell_features(const torch::Tensor& image, int64_t& rows, int64_t& cols) {
  const auto map = trunk->forward(trunk_input(image));  // [1, 64, h, w]
  // unfold flattens each 2x2 block channel-major, like flatten() of a
  // patch's [64, 2, 2] output, so FC1 sees the same feature order.
  const auto blocks = nn::functional::unfold(
      map, nn::functional::UnfoldFuncOptions({2, 2}).stride(kStride / kTrunkStride));  // [1, 256, L]
  rows = (image.size(2) - kPatch) / kStride + 1;
  cols = (image.size(3) - kPatch) / kStride + 1;
  return blocks[0].t().contiguous();  // [rows * cols, 256]
}

AlexNet224Impl::AlexNet224Impl(double dropout, int64_t in_channels) : IntrospectionNetImpl(256 * 6 * 6, 2048, dropout) {
  trunk =
      register_module("trunk", nn::Sequential(nn::Conv2d(nn::Conv2dOptions(in_channels, 64, 11).stride(4).padding(2)),
                                              nn::ReLU(true), nn::MaxPool2d(nn::MaxPool2dOptions(3).stride(2)),
                                              nn::Conv2d(nn::Conv2dOptions(64, 192, 5).padding(2)), nn::ReLU(true),
                                              nn::MaxPool2d(nn::MaxPool2dOptions(3).stride(2)),
                                              nn::Conv2d(nn::Conv2dOptions(192, 384, 3).padding(1)), nn::ReLU(true),
                                              nn::Conv2d(nn::Conv2dOptions(384, 256, 3).padding(1)), nn::ReLU(true),
                                              nn::Conv2d(nn::Conv2dOptions(256, 256, 3).padding(1)), nn::ReLU(true),
                                              nn::MaxPool2d(nn::MaxPool2dOptions(3).stride(2)),
                                              nn::AdaptiveAvgPool2d(nn::AdaptiveAvgPool2dOptions({6, 6}))));
}

torch::Tensor AlexNet224Impl::features(const torch::Tensor& patches) { return trunk->forward(patches).flatten(1); }

std::shared_ptr<IntrospectionNetImpl> make_network(const std::string& architecture, double dropout, int views) {
  if (views != 1 && views != 2) throw std::invalid_argument("views must be 1 or 2, not " + std::to_string(views));
  if (architecture == "slidenet") return SlideNet(dropout, 3 * views).ptr();
  if (architecture == "alexnet") return AlexNet224(dropout, 3 * views).ptr();
  throw std::invalid_argument("unknown architecture '" + architecture + "' (slidenet, alexnet)");
}

int input_size_of(const std::string& architecture) {
  return architecture == "alexnet" ? AlexNet224Impl::kInput : SlideNetImpl::kPatch;
}

}  // namespace ivoa::introspection
