#pragma once
// cv::Mat <-> tensor conversions with the model's normalisation.
#include <vector>

#include <opencv2/core.hpp>
#include <torch/torch.h>

#include "ivoa/introspection/model.hpp"

namespace ivoa::introspection {

// 8-bit BGR image -> [1, 3, H, W] float, RGB, (x/255 - mean) / std.
torch::Tensor image_to_tensor(const cv::Mat& bgr, const ModelInfo& info);
// Patches (8-bit BGR, all the same size) -> [B, 3, S, S], resized to
// info.input_size if needed.
torch::Tensor patches_to_tensor(const std::vector<cv::Mat>& patches, const ModelInfo& info);
// Raw uint8 patches [B, S, S, 3] BGR (e.g. memory-mapped) -> normalised [B, 3, S, S].
torch::Tensor normalize_patches(const torch::Tensor& bgr_uint8, const ModelInfo& info);
// The two steps of normalize_patches, for training-time augmentation in between:
// uint8 BGR [B, S, S, 3] -> float RGB [B, 3, S, S] on [0, 1] ...
torch::Tensor to_unit_rgb(const torch::Tensor& bgr_uint8);
// ... -> (x - mean) / std, resized to info.input_size.
torch::Tensor normalize(const torch::Tensor& unit_rgb, const ModelInfo& info);
// [rows * cols] float tensor -> rows x cols CV_32F.
cv::Mat to_mat(const torch::Tensor& values, int rows, int cols);

}  // namespace ivoa::introspection
