#pragma once
// The DAISY descriptor in the configuration JPP uses (ivoa_jpp_spec.md §1.3),
// our own implementation: smoothed orientation layers of the image gradient,
// sampled at the centre and on Q rings of T points, H bins each, L2
// normalised over the whole vector. With JPP's R = 5, Q = 2, T = 1, H = 1
// that is 3 floats per pixel: the positive horizontal gradient at (x, y),
// (x + 2.5, y) and (x + 5, y).
//
// Layers are computed for the whole image per frame (cheap separable
// filters); descriptors are computed lazily per pixel on first use and
// cached, as in DAISY's "single descriptor mode" that JPP runs.
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

  // 8-bit gray image (rectified). Recomputes the layers and empties the cache.
  void set_image(const cv::Mat& gray);

  // Floats per descriptor ((Q*T+1)*H) and the stride between cached
  // descriptors (padded to a multiple of 4, the padding is zero).
  int size() const { return size_; }
  int stride() const { return stride_; }
  cv::Size image_size() const { return image_size_; }

  // Descriptor of pixel (x, y), which must lie inside the image; computed on
  // first use, then cached until the next set_image.
  const float* at(int x, int y) {
    const size_t i = static_cast<size_t>(y) * static_cast<size_t>(image_size_.width) + static_cast<size_t>(x);
    float* d = &cache_[i * static_cast<size_t>(stride_)];
    if (!computed_[i]) {
      compute(x, y, d);
      computed_[i] = 1;
      ++computed_count_;
    }
    return d;
  }

  // The base layer of orientation bin h (bin 0: positive horizontal
  // gradient of the [0, 1] image, smoothed to sigma 1.6), for texture measures.
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
  struct Sample {
    int cube;       // which smoothed cube it reads
    double dx, dy;  // offset from the pixel, pixels
  };
  void compute(int x, int y, float* out) const;

  DaisyParams params_;
  int size_ = 0, stride_ = 0;
  std::vector<Sample> samples_;
  Reach reach_;
  std::vector<double> cube_increments_;      // incremental blur sigma of cube i from cube i-1
  std::vector<std::vector<cv::Mat>> cubes_;  // [cube][bin], CV_32F
  cv::Size image_size_;
  std::vector<float> cache_;
  std::vector<uint8_t> computed_;
  int64_t computed_count_ = 0;
};

}  // namespace ivoa::stereo
