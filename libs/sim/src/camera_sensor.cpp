#include "camera_sensor.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "noise.hpp"

namespace ivoa::sim::detail {
namespace {

static_assert(sizeof(Rgbf) == 3 * sizeof(float), "Rgbf must be three packed floats");

const std::vector<uint8_t>& gamma_lut(double gamma) {
  static thread_local double cached_gamma = -1;
  static thread_local std::vector<uint8_t> lut(4096);
  if (gamma != cached_gamma) {
    for (int i = 0; i < 4096; ++i)
      lut[static_cast<size_t>(i)] = static_cast<uint8_t>(std::lround(255.0 * std::pow(i / 4095.0, gamma)));
    cached_gamma = gamma;
  }
  return lut;
}

// Horizontal box smear (motion blur while the robot turns), centred.
const std::vector<Rgbf>& smear_rows(const std::vector<Rgbf>& in, int width, int height, int length) {
  thread_local std::vector<Rgbf> out;  // scratch reused across frames, fully written below
  out.resize(in.size());
  const int half = length / 2;
  const float inv = 1.0f / static_cast<float>(length);
  for (int y = 0; y < height; ++y) {
    const Rgbf* row = in.data() + static_cast<size_t>(y) * width;
    Rgbf* dst = out.data() + static_cast<size_t>(y) * width;
    Rgbf sum(0.0f);
    auto at = [&](int x) { return row[std::clamp(x, 0, width - 1)]; };
    for (int k = -half; k < length - half; ++k) sum += at(k);
    for (int x = 0; x < width; ++x) {
      dst[x] = sum * inv;
      sum += at(x + length - half);
      sum = sum - at(x - half);
    }
  }
  return out;
}

}  // namespace

Exposure auto_exposure(const std::vector<Rgbf>& radiance, const CameraSensorConfig& c, double max_exposure_scale) {
  double sum = 0;
  int count = 0;
  for (size_t i = 3; i < radiance.size(); i += 61) {  // sparse metering
    sum += radiance[i].luminance();
    ++count;
  }
  const double mean = std::max(sum / std::max(count, 1), 1e-9);
  double needed = c.target_level * c.full_well / mean;  // electrons x gain per unit radiance
  // Bright lights and sky clip; meter on the clipped signal as a camera does.
  double clipped = 0;
  for (size_t i = 3; i < radiance.size(); i += 61)
    clipped += std::min(1.0, radiance[i].luminance() * needed / c.full_well);
  clipped /= std::max(count, 1);
  if (clipped > 0) needed *= std::clamp(c.target_level / clipped, 1.0, 3.0);
  Exposure e;
  const double t_max = c.max_exposure_ms * max_exposure_scale;
  e.time_ms = needed / c.sensitivity;
  if (e.time_ms > t_max) {
    e.gain = std::min(e.time_ms / t_max, c.max_gain);
    e.time_ms = t_max;
  }
  e.time_ms = std::max(e.time_ms, c.min_exposure_ms);
  e.electrons_per_unit = c.sensitivity * e.time_ms;
  return e;
}

CameraImage expose(const std::vector<Rgbf>& radiance_in, int width, int height, const Exposure& exposure,
                   double sensitivity, const CameraSensorConfig& c, uint64_t frame, uint32_t stream, double smear_px,
                   bool with_saturation) {
  const int smear = c.motion_blur ? static_cast<int>(std::lround(smear_px)) : 0;
  const std::vector<Rgbf>& radiance = smear >= 2 ? smear_rows(radiance_in, width, height, smear) : radiance_in;
  const float* rad = &radiance[0].r;
  const uint8_t* lut = gamma_lut(c.gamma).data();
  const NoiseTable& table = NoiseTable::instance();
  const float* normals = table.normals();
  const float electrons = static_cast<float>(exposure.electrons_per_unit * sensitivity);
  const float to_unit = static_cast<float>(exposure.gain / c.full_well);
  const float read2 = static_cast<float>(c.read_noise * c.read_noise);
  // Reading the table backwards for one camera makes sure the two cameras'
  // noise can never line up as a matchable pattern.
  const int direction = (stream & 1) ? -1 : 1;
  auto digitise = [&](float value, uint32_t idx) {
    const float s = value * electrons;
    const float noisy = s + normals[idx & NoiseTable::kMask] * std::sqrt(std::max(s, 0.0f) + read2);
    const float unit = std::min(std::max(noisy * to_unit, 0.0f), 1.0f);
    return lut[static_cast<int>(unit * 4095.0f + 0.5f)];
  };
  CameraImage out;
  const int W = width;
  if (c.bayer) {
    cv::Mat raw(height, width, CV_8UC1);
    for (int y = 0; y < height; ++y) {
      const float* r0 = rad + static_cast<size_t>(std::max(y - 1, 0)) * W * 3;
      const float* r1 = rad + static_cast<size_t>(y) * W * 3;
      const float* r2 = rad + static_cast<size_t>(std::min(y + 1, height - 1)) * W * 3;
      uint8_t* dst = raw.ptr<uint8_t>(y);
      const uint32_t offset = NoiseTable::offset(frame, stream, static_cast<uint32_t>(y));
      // RGGB: R at (even, even), B at (odd, odd), G elsewhere. Optics: 3x3
      // binomial point spread (sigma ~0.7 px), on the colour the photosite sees.
      auto photosite = [&](int x, int xl, int xr) {
        const int ch = (y & 1) ? ((x & 1) ? 2 : 1) : ((x & 1) ? 1 : 0);
        xl = xl * 3 + ch;
        xr = xr * 3 + ch;
        const int xc = x * 3 + ch;
        const float v = 0.0625f * (r0[xl] + r0[xr] + r2[xl] + r2[xr]) + 0.125f * (r0[xc] + r2[xc] + r1[xl] + r1[xr]) +
                        0.25f * r1[xc];
        dst[x] = digitise(v, offset + static_cast<uint32_t>(direction * x));
      };
      photosite(0, 0, 1);
      for (int x = 1; x + 1 < width; ++x) photosite(x, x - 1, x + 1);
      photosite(width - 1, width - 2, width - 1);
    }
    cv::cvtColor(raw, out.bgr, bayer_to_bgr_code(image_t::PIXEL_FORMAT_BAYER_RGGB));
  } else {
    out.bgr.create(height, width, CV_8UC3);
    for (int y = 0; y < height; ++y) {
      const float* r0 = rad + static_cast<size_t>(std::max(y - 1, 0)) * W * 3;
      const float* r1 = rad + static_cast<size_t>(y) * W * 3;
      const float* r2 = rad + static_cast<size_t>(std::min(y + 1, height - 1)) * W * 3;
      uint8_t* dst = out.bgr.ptr<uint8_t>(y);
      const uint32_t offset = NoiseTable::offset(frame, stream, static_cast<uint32_t>(y));
      for (int x = 0; x < width; ++x)
        for (int ch = 0; ch < 3; ++ch) {
          const int xl = std::max(x - 1, 0) * 3 + ch, xc = x * 3 + ch, xr = std::min(x + 1, W - 1) * 3 + ch;
          const float v = 0.0625f * (r0[xl] + r0[xr] + r2[xl] + r2[xr]) + 0.125f * (r0[xc] + r2[xc] + r1[xl] + r1[xr]) +
                          0.25f * r1[xc];
          dst[x * 3 + (2 - ch)] = digitise(v, offset + static_cast<uint32_t>(direction * (3 * x + ch)));
        }
    }
  }
  if (!with_saturation) return out;
  out.saturated.create(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    const uint8_t* p = out.bgr.ptr<uint8_t>(y);
    uint8_t* s = out.saturated.ptr<uint8_t>(y);
    for (int x = 0; x < width; ++x) s[x] = (p[3 * x] == 255) | (p[3 * x + 1] == 255) | (p[3 * x + 2] == 255);
  }
  return out;
}

}  // namespace ivoa::sim::detail
