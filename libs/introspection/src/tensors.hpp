#pragma once
// cv::Mat <-> tensor conversions with the model's normalisation, and the
// device a model runs on.
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <torch/torch.h>

#include "ivoa/introspection/model.hpp"

namespace ivoa::introspection {

// Views (ModelInfo::views) travel stacked along the rows, as the dataset
// stores them, and become channel groups: view k is channels 3k..3k+2.

// "cpu" or "cuda"; throws ModelError for another name, or for cuda where
// this LibTorch cannot use it (Debian's is CPU-only).
torch::Device device_named(const std::string& name);

// 8-bit BGR image (views x H rows) -> [1, 3 x views, H, W] float, RGB, (x/255 - mean) / std.
torch::Tensor image_to_tensor(const cv::Mat& bgr, const ModelInfo& info);
// Patches (8-bit BGR, all the same size, views x S rows) -> [B, 3 x views, S, S],
// resized to info.input_size if needed.
torch::Tensor patches_to_tensor(const std::vector<cv::Mat>& patches, const ModelInfo& info);
// Raw uint8 patches [B, views x S, S, 3] BGR (e.g. memory-mapped) -> normalised [B, 3 x views, S, S].
torch::Tensor normalize_patches(const torch::Tensor& bgr_uint8, const ModelInfo& info);
// [rows * cols] float tensor -> rows x cols CV_32F.
cv::Mat to_mat(const torch::Tensor& values, int rows, int cols);

}  // namespace ivoa::introspection
