#include "tensors.hpp"

#include <cstring>

#include <opencv2/imgproc.hpp>

namespace ivoa::introspection {
namespace {

// uint8 BGR [B, views x S, S, 3] -> float RGB [B, 3 x views, S, S] on [0, 1].
torch::Tensor to_unit_rgb(const torch::Tensor& bgr_uint8) {
  const int64_t b = bgr_uint8.size(0), s = bgr_uint8.size(2), views = bgr_uint8.size(1) / s;
  // [B, V, S, S, 3]; BGR -> RGB by flipping the channel axis; views become channel groups.
  return bgr_uint8.view({b, views, s, s, 3})
      .flip({4})
      .permute({0, 1, 4, 2, 3})
      .reshape({b, 3 * views, s, s})
      .to(torch::kFloat)
      .div_(255.0);
}

// -> (x - mean) / std, resized to info.input_size.
torch::Tensor normalize(const torch::Tensor& unit_rgb, const ModelInfo& info) {
  const int64_t views = unit_rgb.size(1) / 3;
  const auto mean = torch::tensor({info.mean[0], info.mean[1], info.mean[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  const auto std = torch::tensor({info.std[0], info.std[1], info.std[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  auto x = (unit_rgb - mean.to(unit_rgb.device())) / std.to(unit_rgb.device());
  if (x.size(2) != info.input_size)
    x = torch::nn::functional::interpolate(x, torch::nn::functional::InterpolateFuncOptions()
                                                  .size(std::vector<int64_t>{info.input_size, info.input_size})
                                                  .mode(torch::kBilinear)
                                                  .align_corners(false));
  return x.contiguous();
}

}  // namespace

torch::Tensor normalize_patches(const torch::Tensor& bgr_uint8, const ModelInfo& info) {
  return normalize(to_unit_rgb(bgr_uint8), info);
}

torch::Tensor image_to_tensor(const cv::Mat& bgr, const ModelInfo& info) {
  CV_Assert(bgr.type() == CV_8UC3 && bgr.rows % info.views == 0);
  const int rows = bgr.rows / info.views;
  // One pass per channel straight into the planar float tensor:
  // RGB plane c of view k = (BGR channel 2 - c) / 255, minus mean, over std.
  auto out = torch::empty({1, 3 * info.views, rows, bgr.cols}, torch::kFloat);
  const size_t plane_size = static_cast<size_t>(rows) * bgr.cols;
  for (int k = 0; k < info.views; ++k) {
    std::vector<cv::Mat> channels;
    cv::split(bgr.rowRange(k * rows, (k + 1) * rows), channels);
    for (int c = 0; c < 3; ++c) {
      cv::Mat plane(rows, bgr.cols, CV_32F, out.data_ptr<float>() + static_cast<size_t>(3 * k + c) * plane_size);
      const double scale = 1.0 / (255.0 * info.std[static_cast<size_t>(c)]);
      channels[static_cast<size_t>(2 - c)].convertTo(plane, CV_32F, scale,
                                                     -info.mean[static_cast<size_t>(c)] / info.std[static_cast<size_t>(c)]);
    }
  }
  return out;
}

torch::Tensor patches_to_tensor(const std::vector<cv::Mat>& patches, const ModelInfo& info) {
  if (patches.empty()) return torch::empty({0, 3 * info.views, info.input_size, info.input_size});
  const int s = patches[0].cols, rows = s * info.views;
  auto raw = torch::empty({static_cast<int64_t>(patches.size()), rows, s, 3}, torch::kUInt8);
  const size_t bytes = static_cast<size_t>(rows) * s * 3;
  for (size_t i = 0; i < patches.size(); ++i) {
    CV_Assert(patches[i].type() == CV_8UC3 && patches[i].rows == rows && patches[i].cols == s);
    const cv::Mat p = patches[i].isContinuous() ? patches[i] : patches[i].clone();
    std::memcpy(raw.data_ptr<uint8_t>() + i * bytes, p.data, bytes);
  }
  return normalize_patches(raw, info);
}

cv::Mat to_mat(const torch::Tensor& values, int rows, int cols) {
  const auto v = values.to(torch::kCPU).to(torch::kFloat).contiguous();
  cv::Mat out(rows, cols, CV_32F);
  std::memcpy(out.data, v.data_ptr<float>(), static_cast<size_t>(rows) * cols * sizeof(float));
  return out;
}

}  // namespace ivoa::introspection
