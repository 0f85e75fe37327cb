#include "tensors.hpp"

#include <cstring>

#include <ATen/Parallel.h>
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

// Resized to the network's input (AlexNet's 224) where the patches differ.
torch::Tensor resized_to_input(const torch::Tensor& x, const ModelInfo& info) {
  if (x.size(2) == info.input_size) return x.contiguous();
  return torch::nn::functional::interpolate(x, torch::nn::functional::InterpolateFuncOptions()
                                                   .size(std::vector<int64_t>{info.input_size, info.input_size})
                                                   .mode(torch::kBilinear)
                                                   .align_corners(false))
      .contiguous();
}

// (x - mean) / std per RGB channel of every view.
torch::Tensor standardize(const torch::Tensor& unit_rgb, const ModelInfo& info) {
  const int64_t views = unit_rgb.size(1) / 3;
  const auto mean =
      torch::tensor({info.mean[0], info.mean[1], info.mean[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  const auto std = torch::tensor({info.std[0], info.std[1], info.std[2]}).view({1, 3, 1, 1}).repeat({1, views, 1, 1});
  return (unit_rgb - mean.to(unit_rgb.device())) / std.to(unit_rgb.device());
}

// The standardized value of each 8-bit level per RGB channel, [3, 256]:
// computed by the very operations normalize_patches() applies, each exactly
// rounded, so a lookup gives the same floats bit for bit.
torch::Tensor level_table(const ModelInfo& info) {
  const auto levels = torch::arange(256, torch::kInt).to(torch::kUInt8).view({1, 1, 1, 256}).expand({1, 3, 1, 256});
  return standardize(levels.to(torch::kFloat).div_(255.0), info).view({3, 256}).contiguous();
}

// One patch (8-bit BGR, views x S rows) -> its 3 x views planes of S x S floats.
void fill_patch(const cv::Mat& patch, int views, const float* table, float* out) {
  const int s = patch.cols;
  const size_t plane = static_cast<size_t>(s) * s;
  for (int v = 0; v < views; ++v)
    for (int y = 0; y < s; ++y) {
      const uint8_t* bgr = patch.ptr<uint8_t>(v * s + y);
      float* r = out + static_cast<size_t>(3 * v) * plane + static_cast<size_t>(y) * s;
      float* g = r + plane;
      float* b = g + plane;
      for (int x = 0; x < s; ++x) {
        b[x] = table[2 * 256 + bgr[3 * x]];
        g[x] = table[256 + bgr[3 * x + 1]];
        r[x] = table[bgr[3 * x + 2]];
      }
    }
}

}  // namespace

torch::Device device_named(const std::string& name) {
  if (name == "cpu") return torch::kCPU;
  if (name == "cuda") {
    if (!torch::cuda::is_available()) throw ModelError("device 'cuda' requested but this LibTorch has no usable CUDA");
    return torch::kCUDA;
  }
  throw ModelError("unknown device '" + name + "' (cpu, cuda)");
}

torch::Tensor normalize_patches(const torch::Tensor& bgr_uint8, const ModelInfo& info) {
  return resized_to_input(standardize(to_unit_rgb(bgr_uint8), info), info);
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
      channels[static_cast<size_t>(2 - c)].convertTo(
          plane, CV_32F, scale, -info.mean[static_cast<size_t>(c)] / info.std[static_cast<size_t>(c)]);
    }
  }
  return out;
}

torch::Tensor patches_to_tensor(const std::vector<cv::Mat>& patches, const ModelInfo& info) {
  if (patches.empty()) return torch::empty({0, 3 * info.views, info.input_size, info.input_size});
  const int s = patches[0].cols;
  for (const auto& p : patches) CV_Assert(p.type() == CV_8UC3 && p.rows == s * info.views && p.cols == s);
  // One table lookup per value instead of a chain of whole-batch tensor
  // passes (flip, permute, convert, scale, standardize), same result.
  const auto table = level_table(info);
  auto out = torch::empty({static_cast<int64_t>(patches.size()), 3 * info.views, s, s}, torch::kFloat);
  const size_t patch_floats = static_cast<size_t>(3 * info.views) * s * s;
  at::parallel_for(0, static_cast<int64_t>(patches.size()), 1, [&](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i)
      fill_patch(patches[static_cast<size_t>(i)], info.views, table.data_ptr<float>(),
                 out.data_ptr<float>() + static_cast<size_t>(i) * patch_floats);
  });
  return resized_to_input(out, info);
}

cv::Mat to_mat(const torch::Tensor& values, int rows, int cols) {
  const auto v = values.to(torch::kCPU).to(torch::kFloat).contiguous();
  cv::Mat out(rows, cols, CV_32F);
  std::memcpy(out.data, v.data_ptr<float>(), static_cast<size_t>(rows) * cols * sizeof(float));
  return out;
}

}  // namespace ivoa::introspection
