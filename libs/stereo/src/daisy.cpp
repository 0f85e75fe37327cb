#include "ivoa/stereo/daisy.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace ivoa::stereo {
namespace {

// DAISY's pipeline: the [0, 1] image is pre-blurred with sigma 0.5 (5 taps)
// and the gradient layers are smoothed to a total sigma of 1.6.
constexpr double kImageSigma = 0.5;
constexpr double kLayerSigma = 1.6;

cv::Mat blur(const cv::Mat& in, double sigma) {
  const int half = static_cast<int>(std::ceil(3.0 * sigma));
  cv::Mat out;
  cv::GaussianBlur(in, out, cv::Size(2 * half + 1, 2 * half + 1), sigma, sigma, cv::BORDER_REPLICATE);
  return out;
}

// Bilinear read of a CV_32F layer; 0 where the sample's neighbourhood leaves
// the image (DAISY leaves out-of-image samples empty).
float sample(const cv::Mat& layer, double x, double y) {
  if (x < 0 || y < 0 || x > layer.cols - 1 || y > layer.rows - 1) return 0.f;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const int x1 = fx > 0 ? x0 + 1 : x0, y1 = fy > 0 ? y0 + 1 : y0;
  const float* r0 = layer.ptr<float>(y0);
  const float* r1 = layer.ptr<float>(y1);
  const double top = (1 - fx) * r0[x0] + fx * r0[x1];
  const double bottom = (1 - fx) * r1[x0] + fx * r1[x1];
  return static_cast<float>((1 - fy) * top + fy * bottom);
}

}  // namespace

DaisyDescriptors::DaisyDescriptors(const DaisyParams& params) : params_(params) {
  if (!(params.R > 0) || params.Q < 1 || params.T < 1 || params.H < 1)
    throw std::invalid_argument("DAISY parameters need R > 0 and Q, T, H >= 1");
  size_ = (params.Q * params.T + 1) * params.H;
  stride_ = (size_ + 3) / 4 * 4;
  // Samples: the centre, then ring by ring, angle by angle (DAISY's order).
  // Ring r (1..Q) has radius r*R/Q. JPP's DAISY reads cube r-1 for ring r
  // and cube 0 for the centre (an index offset in its code: the centre and
  // ring 1 both read the base layer). We reproduce that quirk, since the
  // thresholds were tuned on it; the last cube is then never read.
  samples_.push_back({0, 0.0, 0.0});
  for (int r = 1; r <= params.Q; ++r) {
    const double radius = r * params.R / params.Q;
    for (int t = 0; t < params.T; ++t) {
      const double angle = 2.0 * M_PI * t / params.T;
      samples_.push_back({r - 1, radius * std::cos(angle), radius * std::sin(angle)});
    }
  }
  for (const Sample& s : samples_) {
    reach_.left = std::max(reach_.left, static_cast<int>(std::ceil(-s.dx - 1e-9)));
    reach_.right = std::max(reach_.right, static_cast<int>(std::ceil(s.dx - 1e-9)));
    reach_.up = std::max(reach_.up, static_cast<int>(std::ceil(-s.dy - 1e-9)));
    reach_.down = std::max(reach_.down, static_cast<int>(std::ceil(s.dy - 1e-9)));
  }
  // Cube i >= 1 adds ring sigma i*R/(2Q) to the base layer, incrementally.
  for (int i = 1; i < params.Q; ++i) {
    const double now = i * params.R / (2.0 * params.Q), before = (i - 1) * params.R / (2.0 * params.Q);
    cube_increments_.push_back(std::sqrt(now * now - before * before));
  }
}

void DaisyDescriptors::set_image(const cv::Mat& gray) {
  if (gray.type() != CV_8UC1 || gray.empty()) throw std::invalid_argument("DAISY needs a non-empty 8-bit gray image");
  image_size_ = gray.size();
  cv::Mat image;
  gray.convertTo(image, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(image, image, cv::Size(5, 5), kImageSigma, kImageSigma, cv::BORDER_REPLICATE);
  // Central differences, as DAISY's gradient.
  const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.f, 0.5f);
  cv::Mat dx, dy;
  cv::filter2D(image, dx, CV_32F, kx, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  if (params_.H > 1) cv::filter2D(image, dy, CV_32F, kx.t(), cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);

  const double base_sigma = std::sqrt(kLayerSigma * kLayerSigma - kImageSigma * kImageSigma);
  cubes_.assign(static_cast<size_t>(params_.Q), {});
  for (int h = 0; h < params_.H; ++h) {
    // Orientation bin h: the positive part of the gradient along angle 2*pi*h/H.
    const double angle = 2.0 * M_PI * h / params_.H;
    cv::Mat layer = h == 0 ? dx.clone() : std::cos(angle) * dx + std::sin(angle) * dy;
    layer = cv::max(layer, 0.0);
    cubes_[0].push_back(blur(layer, base_sigma));
    for (int i = 1; i < params_.Q; ++i)
      cubes_[static_cast<size_t>(i)].push_back(blur(cubes_[static_cast<size_t>(i - 1)].back(),
                                                    cube_increments_[static_cast<size_t>(i - 1)]));
  }
  // compute() writes every used float; the padding stays zero from allocation.
  const size_t pixels = static_cast<size_t>(image_size_.area());
  if (cache_.size() != pixels * static_cast<size_t>(stride_)) cache_.assign(pixels * static_cast<size_t>(stride_), 0.f);
  computed_.assign(pixels, 0);
  computed_count_ = 0;
}

void DaisyDescriptors::compute(int x, int y, float* out) const {
  int k = 0;
  for (const Sample& s : samples_) {
    const auto& cube = cubes_[static_cast<size_t>(s.cube)];
    for (int h = 0; h < params_.H; ++h) out[k++] = sample(cube[static_cast<size_t>(h)], x + s.dx, y + s.dy);
  }
  double norm = 0;
  for (int i = 0; i < size_; ++i) norm += static_cast<double>(out[i]) * out[i];
  // DAISY "full" normalisation; an all-zero (texture-less) vector stays zero.
  if (norm > 0) {
    const float inv = static_cast<float>(1.0 / std::sqrt(norm));
    for (int i = 0; i < size_; ++i) out[i] *= inv;
  }
}

}  // namespace ivoa::stereo
