#pragma once
// Conversions between LCM image messages and cv::Mat.
#include <cstdint>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace ivoa {
class image_t;
class depth_image_t;
class stereo_image_t;

// Thrown for an image message that cannot be decoded; what() says why.
class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ColorOutput { kBgr, kGray };

// The most pixels an image message or a calibrated camera may have (64 Mi
// px, past any stereo or depth camera's sensor). Declared sizes are checked
// against it before anything is allocated or decompressed: a 584 kB PNG can
// claim 1.8 GB of pixels.
constexpr int64_t kMaxImagePixels = int64_t{1} << 26;

// Decodes any supported image_t (gray, RGB, BGR, the four Bayer layouts,
// JPEG, PNG) into an 8-bit BGR or gray cv::Mat that owns its data. A JPEG
// or PNG is decompressed only if its header's size is the message's.
cv::Mat decode_image(const image_t& msg, ColorOutput output = ColorOutput::kBgr);

// The most a stereo pair's two exposures, or an exposure and the pair's
// utime, may lie apart: half the frame period of a 1 Hz rig.
constexpr int64_t kMaxStereoSkewUs = 500'000;
// Empty if the pair's times agree (an image utime of 0 is unknown and not
// compared), otherwise which are how far apart: images 5 s apart were
// matched as one view of the world.
std::string stereo_times_error(const stereo_image_t& msg);

// Encodes an 8-bit BGR (3 channels) or gray image. `pixelformat` picks the
// wire format: GRAY, RGB, BGR, a BAYER_* layout (mosaiced here), JPEG or PNG.
image_t encode_image(const cv::Mat& image, int32_t pixelformat, int64_t utime, int jpeg_quality = 90);

// Samples a BGR image through a Bayer colour filter array (one 8-bit
// channel), as a Bayer sensor would record it.
cv::Mat mosaic_bayer(const cv::Mat& bgr, int32_t bayer_pixelformat);

// The OpenCV conversion code that demosaics a Bayer layout to BGR. Note the
// naming offset: GenICam BayerRG8 (row 0 = R G) is cv::COLOR_BayerBG2BGR.
int bayer_to_bgr_code(int32_t bayer_pixelformat);
bool is_bayer(int32_t pixelformat);
std::string pixelformat_name(int32_t pixelformat);

// Depth images: CV_16UC1 millimetres, 0 = invalid.
cv::Mat decode_depth(const depth_image_t& msg);
depth_image_t encode_depth(const cv::Mat& depth_mm, double fx, double fy, double cx, double cy, int64_t utime);

}  // namespace ivoa
