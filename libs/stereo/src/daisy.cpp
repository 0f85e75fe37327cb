#include "ivoa/stereo/daisy.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ivoa::stereo {
namespace {

// DAISY's pipeline: the [0, 1] image is pre-blurred with sigma 0.5 (5 taps)
// and the gradient layers are smoothed to a total sigma of 1.6.
constexpr double kImageSigma = 0.5;
constexpr double kLayerSigma = 1.6;
// Filters run on a region only; ISOLATED makes them replicate its edge
// instead of reading (not computed) pixels outside it.
constexpr int kBorder = cv::BORDER_REPLICATE | cv::BORDER_ISOLATED;

constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
constexpr float kTinyNorm = 1e-30f;

// A normalised component (already * kScale, so in [0, 255]) to 8 bits.
inline uint8_t quantize(float scaled) { return static_cast<uint8_t>(scaled + 0.5f); }

int half_support(double sigma) { return static_cast<int>(std::ceil(3.0 * sigma)); }

void blur_into(const cv::Mat& in, cv::Mat out, double sigma) {
  const int k = 2 * half_support(sigma) + 1;
  cv::GaussianBlur(in, out, cv::Size(k, k), sigma, sigma, kBorder);
}

}  // namespace

DaisyDescriptors::DaisyDescriptors(const DaisyParams& params) : params_(params) {
  if (!(params.R > 0) || params.Q < 1 || params.T < 1 || params.H < 1)
    throw std::invalid_argument("DAISY parameters need R > 0 and Q, T, H >= 1");
  size_ = (params.Q * params.T + 1) * params.H;
  stride_ = (size_ + 3) / 4 * 4;
  scratch_.resize(static_cast<size_t>(size_));
  // Samples: the centre, then ring by ring, angle by angle (DAISY's order).
  // Ring r (1..Q) has radius r*R/Q. JPP's DAISY reads cube r-1 for ring r
  // and cube 0 for the centre (an index offset in its code: the centre and
  // ring 1 both read the base layer). We reproduce that quirk, since the
  // thresholds were tuned on it; the last cube is then never read.
  auto add_tap = [&](int cube, double dx, double dy) {
    const double fx0 = std::floor(dx), fy0 = std::floor(dy);
    const auto fx = static_cast<float>(dx - fx0), fy = static_cast<float>(dy - fy0);
    taps_.push_back({cube, static_cast<int>(fx0), static_cast<int>(fy0), (1 - fx) * (1 - fy), fx * (1 - fy),
                     (1 - fx) * fy, fx * fy});
    reach_.left = std::max(reach_.left, static_cast<int>(std::ceil(-dx - 1e-9)));
    reach_.right = std::max(reach_.right, static_cast<int>(std::ceil(dx - 1e-9)));
    reach_.up = std::max(reach_.up, static_cast<int>(std::ceil(-dy - 1e-9)));
    reach_.down = std::max(reach_.down, static_cast<int>(std::ceil(dy - 1e-9)));
  };
  add_tap(0, 0.0, 0.0);
  for (int r = 1; r <= params.Q; ++r) {
    const double radius = r * params.R / params.Q;
    for (int t = 0; t < params.T; ++t) {
      const double angle = 2.0 * M_PI * t / params.T;
      add_tap(r - 1, radius * std::cos(angle), radius * std::sin(angle));
    }
  }
  row_taps_ = params.H == 1 && taps_.size() <= kMaxRowTaps;
  for (const Tap& tap : taps_) row_taps_ = row_taps_ && tap.dy == 0 && tap.w01 == 0 && tap.w11 == 0;
  // Cube i >= 1 adds ring sigma i*R/(2Q) to the base layer, incrementally.
  const double base_sigma = std::sqrt(kLayerSigma * kLayerSigma - kImageSigma * kImageSigma);
  filter_margin_ = half_support(kImageSigma) + 1 + half_support(base_sigma);
  for (int i = 1; i < params.Q; ++i) {
    const double now = i * params.R / (2.0 * params.Q), before = (i - 1) * params.R / (2.0 * params.Q);
    cube_increments_.push_back(std::sqrt(now * now - before * before));
    filter_margin_ += half_support(cube_increments_.back());
  }
}

cv::Rect DaisyDescriptors::region_with_margin(cv::Rect region, cv::Size size) const {
  const cv::Rect grown(region.x - reach_.left - filter_margin_, region.y - reach_.up - filter_margin_,
                       region.width + reach_.left + reach_.right + 2 * filter_margin_,
                       region.height + reach_.up + reach_.down + 2 * filter_margin_);
  return grown & cv::Rect(cv::Point(0, 0), size);
}

void DaisyDescriptors::set_image(const cv::Mat& gray, cv::Rect region) {
  if (gray.type() != CV_8UC1 || gray.empty()) throw std::invalid_argument("DAISY needs a non-empty 8-bit gray image");
  const cv::Rect full(cv::Point(0, 0), gray.size());
  region_ = region.area() > 0 ? region & full : full;
  const cv::Rect work = region_with_margin(region_, gray.size());
  if (image_size_ != gray.size() || cubes_.empty()) {
    image_size_ = gray.size();
    cubes_.assign(static_cast<size_t>(params_.Q), std::vector<cv::Mat>(static_cast<size_t>(params_.H)));
    for (auto& cube : cubes_)
      for (cv::Mat& layer : cube) layer = cv::Mat::zeros(image_size_, CV_32F);
    // compute() writes every used float; the padding stays zero from here on.
    // + kReadPadding: the matcher reads whole 16-byte blocks at a row's end.
    cache_.assign(static_cast<size_t>(image_size_.area()) * static_cast<size_t>(stride_) + kReadPadding, 0);
  }
  cv::Mat image;
  gray(work).convertTo(image, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(image, image, cv::Size(5, 5), kImageSigma, kImageSigma, kBorder);
  // Central differences, as DAISY's gradient.
  const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.f, 0.5f);
  cv::Mat dx, dy;
  cv::filter2D(image, dx, CV_32F, kx, cv::Point(-1, -1), 0, kBorder);
  if (params_.H > 1) cv::filter2D(image, dy, CV_32F, kx.t(), cv::Point(-1, -1), 0, kBorder);
  const double base_sigma = std::sqrt(kLayerSigma * kLayerSigma - kImageSigma * kImageSigma);
  for (int h = 0; h < params_.H; ++h) {
    // Orientation bin h: the positive part of the gradient along angle 2*pi*h/H.
    const double angle = 2.0 * M_PI * h / params_.H;
    cv::Mat layer = h == 0 ? dx : std::cos(angle) * dx + std::sin(angle) * dy;
    layer = cv::max(layer, 0.0);
    const auto bin = static_cast<size_t>(h);
    blur_into(layer, cubes_[0][bin](work), base_sigma);
    for (size_t i = 1; i < cubes_.size(); ++i)
      blur_into(cubes_[i - 1][bin](work), cubes_[i][bin](work), cube_increments_[i - 1]);
  }
  chunks_per_row_ = (image_size_.width + kChunk - 1) / kChunk;
  computed_.assign(static_cast<size_t>(chunks_per_row_) * static_cast<size_t>(image_size_.height), 0);
  computed_count_ = 0;
}

float DaisyDescriptors::sample(const Tap& tap, int h, int x, int y) const {
  const cv::Mat& layer = cubes_[static_cast<size_t>(tap.cube)][static_cast<size_t>(h)];
  const int xs = x + tap.dx, ys = y + tap.dy;
  if (xs >= 0 && ys >= 0 && xs + 1 < layer.cols && ys + 1 < layer.rows) {
    const float* r0 = layer.ptr<float>(ys);
    const float* r1 = layer.ptr<float>(ys + 1);
    return tap.w00 * r0[xs] + tap.w10 * r0[xs + 1] + tap.w01 * r1[xs] + tap.w11 * r1[xs + 1];
  }
  // At the border: a sample needing a pixel outside the image is empty (as
  // in DAISY); weights of zero need no pixel.
  float sum = 0;
  const float weights[4] = {tap.w00, tap.w10, tap.w01, tap.w11};
  for (int k = 0; k < 4; ++k) {
    if (weights[k] == 0) continue;
    const int px = xs + (k & 1), py = ys + (k >> 1);
    if (px < 0 || py < 0 || px >= layer.cols || py >= layer.rows) return 0.f;
    sum += weights[k] * layer.at<float>(py, px);
  }
  return sum;
}

void DaisyDescriptors::compute_run(int y, int x0, int x1) {
  uint8_t* row =
      &cache_[static_cast<size_t>(y) * static_cast<size_t>(image_size_.width) * static_cast<size_t>(stride_)];
  auto compute_each = [&](int from, int to) {
    for (int x = from; x <= to; ++x) compute(x, y, row + static_cast<size_t>(x) * static_cast<size_t>(stride_));
  };
  // The fast path needs every sample inside the image; the few pixels at
  // the borders (and other configurations) take the general one.
  const int fast_lo = row_taps_ ? std::max(x0, reach_.left) : x1 + 1;
  const int fast_hi = row_taps_ ? std::min(x1, image_size_.width - 2 - reach_.right) : x1;
  if (fast_lo <= fast_hi) {
    compute_each(x0, fast_lo - 1);
    compute_row_taps(y, fast_lo, fast_hi);
    compute_each(fast_hi + 1, x1);
  } else {
    compute_each(x0, x1);
  }
  computed_count_ += x1 - x0 + 1;
}

void DaisyDescriptors::compute_row_taps(int y, int x0, int x1) {
  const size_t n = taps_.size();
  const float* rows[kMaxRowTaps];
  float w0[kMaxRowTaps], w1[kMaxRowTaps];
  for (size_t k = 0; k < n; ++k) {
    rows[k] = cubes_[static_cast<size_t>(taps_[k].cube)][0].ptr<float>(y) + taps_[k].dx;
    w0[k] = taps_[k].w00;
    w1[k] = taps_[k].w10;
  }
  const auto stride = static_cast<size_t>(stride_);
  uint8_t* out =
      &cache_[(static_cast<size_t>(y) * static_cast<size_t>(image_size_.width) + static_cast<size_t>(x0)) * stride];
  int x = x0;
#if defined(__SSE2__)
  if (n == 3 && stride == 4 && kLittleEndian) {
    // JPP's descriptor, four pixels at a time: three samples, full
    // normalisation, and the three bytes (plus the zero pad) of each pixel
    // packed into one 32-bit word. Same arithmetic as the scalar loop below.
    const __m128 scale = _mm_set1_ps(kScale), half = _mm_set1_ps(0.5f), tiny = _mm_set1_ps(kTinyNorm);
    auto component = [&](size_t k, int at) {
      return _mm_add_ps(_mm_mul_ps(_mm_set1_ps(w0[k]), _mm_loadu_ps(rows[k] + at)),
                        _mm_mul_ps(_mm_set1_ps(w1[k]), _mm_loadu_ps(rows[k] + at + 1)));
    };
    for (; x + 3 <= x1; x += 4, out += 4 * stride) {
      const __m128 a = component(0, x), b = component(1, x), c = component(2, x);
      const __m128 norm = _mm_add_ps(_mm_add_ps(_mm_mul_ps(a, a), _mm_mul_ps(b, b)), _mm_mul_ps(c, c));
      const __m128 inv = _mm_div_ps(scale, _mm_sqrt_ps(_mm_add_ps(norm, tiny)));
      const __m128i qa = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(a, inv), half));
      const __m128i qb = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(b, inv), half));
      const __m128i qc = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(c, inv), half));
      const __m128i words = _mm_or_si128(qa, _mm_or_si128(_mm_slli_epi32(qb, 8), _mm_slli_epi32(qc, 16)));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out), words);
    }
  }
#endif
  for (; x <= x1; ++x, out += stride) {
    float v[kMaxRowTaps];
    float norm = 0;
    for (size_t k = 0; k < n; ++k) {
      v[k] = w0[k] * rows[k][x] + w1[k] * rows[k][x + 1];
      norm += v[k] * v[k];
    }
    // DAISY "full" normalisation. The tiny bias keeps an all-zero
    // (texture-less) vector zero without a branch; real norms are > 1e-10.
    const float inv = kScale / std::sqrt(norm + kTinyNorm);
    for (size_t k = 0; k < n; ++k) out[k] = quantize(v[k] * inv);
  }
}

void DaisyDescriptors::compute(int x, int y, uint8_t* out) {
  size_t k = 0;
  for (const Tap& tap : taps_)
    for (int h = 0; h < params_.H; ++h) scratch_[k++] = sample(tap, h, x, y);
  float norm = 0;
  for (float c : scratch_) norm += c * c;
  // DAISY "full" normalisation, as in compute_row_taps.
  const float inv = kScale / std::sqrt(norm + kTinyNorm);
  for (size_t i = 0; i < scratch_.size(); ++i) out[i] = quantize(scratch_[i] * inv);
}

}  // namespace ivoa::stereo
