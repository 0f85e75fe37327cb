#pragma once
// Cutting introspection patches out of the left image, and summarising the
// simulator's per-pixel truth under a patch.
#include <cstdint>

#include <opencv2/core.hpp>

namespace ivoa::dataset {

// The patch_size square centred on (u, v) (core's patch_rect), copied; empty
// if it does not lie fully inside the image.
cv::Mat extract_patch(const cv::Mat& image, double u, double v, int patch_size);

struct PatchTruth {
  int32_t phenomena = 0;   // OR of the phenomenon bits in the patch centre
  int32_t phenomenon = 0;  // the bit covering most of the centre (0 none)
  int32_t surface = 255;   // the surface covering most of the centre
};

// Truth over the central half of the patch (the region around the ground
// point that decides the label, not the surroundings the CNN also sees).
PatchTruth summarize_truth(const cv::Mat& phenomena, const cv::Mat& surface, double u, double v, int patch_size);

}  // namespace ivoa::dataset
