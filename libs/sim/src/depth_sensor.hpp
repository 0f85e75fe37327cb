#pragma once
// A Kinect-like structured-light depth sensor applied to traced ranges:
// range limits, noise growing with z^2, millimetre quantisation, shadows
// where the IR projector cannot see, invalid pixels at depth edges, and
// dropouts on dark, mirror-like and sunlit surfaces (in blobs, as real ones).
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/sim/sensors.hpp"
#include "tracer.hpp"

namespace ivoa::sim::detail {

// ranged: width x height traced pixels; focal: pixels; range in metres.
cv::Mat depth_image(const std::vector<Ranged>& ranged, int width, int height, double focal, double min_range,
                    double max_range, const DepthSensorConfig& config, uint64_t frame);

}  // namespace ivoa::sim::detail
