#pragma once
// The DAISY descriptor in the configuration JPP uses (ivoa_jpp_spec.md §1.3),
// our own implementation: smoothed orientation layers of the image gradient,
// sampled at the centre and on Q rings of T points, H bins each, L2
// normalised over the whole vector. With JPP's R = 5, Q = 2, T = 1, H = 1
// that is 3 floats per pixel: the positive horizontal gradient at (x, y),
// (x + 2.5, y) and (x + 5, y).
//
// Layers are computed per frame with separable filters, over the whole image
// or only a region that will be asked for; descriptors are computed lazily
// on first use and cached, as in DAISY's "single descriptor mode" that JPP
// runs. Cached components are stored as 8-bit fixed point (value * 255; JPP
// keeps floats): a window cost then sums byte differences, which is 4x less
// memory to stream, and moves a per-pixel L1 distance by at most 3/510.
#include <algorithm>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace ivoa::stereo {

struct DaisyParams {
  double R = 5.0;  // radius of the outermost ring, pixels
  int Q = 2;       // rings
  int T = 1;       // sample angles per ring
  int H = 1;       // orientation bins
};

class DaisyDescriptors {
 public:
  explicit DaisyDescriptors(const DaisyParams& params);

  // 8-bit gray image (rectified). Recomputes the layers and empties the
  // cache. Descriptors may then be asked for inside `region` only (empty:
  // the whole image); the image must be valid within region_with_margin().
  void set_image(const cv::Mat& gray, cv::Rect region = {});

  // Components per descriptor ((Q*T+1)*H) and the stride between cached
  // descriptors (padded to a multiple of 4, the padding is zero).
  int size() const { return size_; }
  int stride() const { return stride_; }
  cv::Size image_size() const { return image_size_; }
  cv::Rect region() const { return region_; }

  // The image area the layers of `region` depend on (sample reach plus
  // filter support), clipped to an image of `size`.
  cv::Rect region_with_margin(cv::Rect region, cv::Size size) const;

  // Cached components are value * kScale, rounded, in one byte each.
  static constexpr float kScale = 255.f;
  // The cache may be read up to this many bytes past a descriptor's end.
  static constexpr size_t kReadPadding = 16;
  // Descriptors are computed on first use in aligned chunks of this many
  // pixels of a row (JPP: one pixel at a time). Streaming a short run costs
  // about what one scattered pixel does, and windows overlap heavily.
  static constexpr int kChunk = 16;

  // Descriptors of row y, columns x0..x1 (inside region()), computed where
  // not cached yet. Returns row y of the cache: the descriptor of column x
  // is at [x * stride(), x * stride() + size()).
  const uint8_t* row(int y, int x0, int x1) {
    uint8_t* done = &computed_[static_cast<size_t>(y) * static_cast<size_t>(chunks_per_row_)];
    for (int c = x0 / kChunk; c <= x1 / kChunk; ++c) {
      if (done[c]) continue;
      compute_run(y, c * kChunk, std::min(image_size_.width, (c + 1) * kChunk) - 1);
      done[c] = 1;
    }
    return &cache_[static_cast<size_t>(y) * static_cast<size_t>(image_size_.width) * static_cast<size_t>(stride_)];
  }
  const uint8_t* at(int x, int y) { return row(y, x, x) + static_cast<size_t>(x) * static_cast<size_t>(stride_); }
  // Component i of a descriptor as a value in [0, 1].
  static float value(const uint8_t* descriptor, int i) { return descriptor[i] / kScale; }

  // The base layer of orientation bin h (bin 0: positive horizontal
  // gradient of the [0, 1] image, smoothed to sigma 1.6), valid in region().
  const cv::Mat& base_layer(int h = 0) const { return cubes_[0][static_cast<size_t>(h)]; }

  // How far the sample points reach from the pixel, whole pixels: a
  // descriptor is complete only at least this far inside the image.
  struct Reach {
    int left = 0, right = 0, up = 0, down = 0;
  };
  Reach reach() const { return reach_; }

  // Descriptors computed since the last set_image (for benchmarks).
  int64_t computed_count() const { return computed_count_; }

 private:
  // One bilinear sample point: integer offset, weights, cube it reads.
  struct Tap {
    int cube;
    int dx, dy;
    float w00, w10, w01, w11;
  };
  void compute_run(int y, int x0, int x1);
  void compute(int x, int y, uint8_t* out);
  // JPP's case (H = 1, every sample on the pixel's row), on a run of pixels
  // whose samples are all inside the image.
  void compute_row_taps(int y, int x0, int x1);
  float sample(const Tap& tap, int h, int x, int y) const;

  DaisyParams params_;
  int size_ = 0, stride_ = 0, filter_margin_ = 0;
  std::vector<Tap> taps_;
  static constexpr size_t kMaxRowTaps = 8;
  bool row_taps_ = false;  // H == 1, at most kMaxRowTaps taps, all on their pixel's row
  Reach reach_;
  std::vector<double> cube_increments_;      // incremental blur sigma of cube i from cube i-1
  std::vector<std::vector<cv::Mat>> cubes_;  // [cube][bin], CV_32F, full image size
  cv::Size image_size_;
  cv::Rect region_;
  std::vector<float> scratch_;  // one descriptor's values, for compute()
  std::vector<uint8_t> cache_;
  int chunks_per_row_ = 0;
  std::vector<uint8_t> computed_;  // per chunk
  int64_t computed_count_ = 0;
};

}  // namespace ivoa::stereo
