#pragma once
// The camera's imaging chain, applied to the rendered radiance: auto
// exposure (time first, then gain), motion smear, optics blur, Bayer
// colour filter, shot and read noise, clipping, gamma, 8 bits, demosaic.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "color.hpp"
#include "ivoa/sim/sensors.hpp"

namespace ivoa::sim::detail {

struct Exposure {
  double time_ms = 1;
  double gain = 1;
  double electrons_per_unit = 1;  // electrons (times gain) per unit radiance
};

// Auto exposure for a frame, metered on `radiance` (sparse samples).
Exposure auto_exposure(const std::vector<Rgbf>& radiance, const CameraSensorConfig& config, double max_exposure_scale);

struct CameraImage {
  cv::Mat bgr;        // CV_8UC3
  cv::Mat saturated;  // CV_8UC1, 1 where a channel clipped
};

// stream: distinguishes the cameras' noise; smear_px: horizontal motion blur length.
// with_saturation: also fill CameraImage::saturated.
CameraImage expose(const std::vector<Rgbf>& radiance, int width, int height, const Exposure& exposure,
                   double sensitivity, const CameraSensorConfig& config, uint64_t frame, uint32_t stream,
                   double smear_px, bool with_saturation);

}  // namespace ivoa::sim::detail
