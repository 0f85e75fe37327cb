#include "disparity_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace ivoa::stereo_eval {
namespace {

bool host_is_little_endian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void mark_unknown(cv::Mat& disparity) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  disparity.forEach<float>([nan](float& d, const int*) {
    if (!std::isfinite(d) || d <= 0) d = nan;
  });
}

// A JPEG whose last kilobyte holds no end-of-image marker (FF D9; entropy-
// coded data never contains one) was cut short.
bool jpeg_cut_short(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char start[2] = {};
  if (!in.read(start, 2) || start[0] != '\xFF' || start[1] != '\xD8') return false;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg(), tail = std::min<std::streamoff>(size, 1024);
  std::string last(static_cast<size_t>(tail), '\0');
  in.seekg(size - tail);
  in.read(last.data(), tail);
  return last.find("\xFF\xD9") == std::string::npos;
}

}  // namespace

cv::Mat read_image(const std::string& path, int imread_flags) {
  if (!std::filesystem::exists(path)) throw DisparityFileError(path + ": no such file");
  if (jpeg_cut_short(path)) throw DisparityFileError(path + ": a JPEG cut short (no end-of-image marker)");
  cv::Mat image = cv::imread(path, imread_flags);
  if (image.empty()) throw DisparityFileError(path + ": cannot read the image");
  return image;
}

cv::Mat read_pfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DisparityFileError(path + ": cannot open");
  std::string magic;
  int width = 0, height = 0;
  double scale = 0;
  in >> magic >> width >> height >> scale;
  if (!in || (magic != "Pf" && magic != "PF") || width <= 0 || height <= 0 || scale == 0)
    throw DisparityFileError(path + ": not a PFM file (expected 'Pf'/'PF', size and scale)");
  in.get();  // the single whitespace after the header
  const int channels = magic == "PF" ? 3 : 1;
  cv::Mat raw(height, width, CV_32FC(channels));
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(channels) * sizeof(float);
  // PFM stores the bottom row first.
  for (int v = height - 1; v >= 0; --v) {
    in.read(reinterpret_cast<char*>(raw.ptr(v)), static_cast<std::streamsize>(row_bytes));
    if (!in) throw DisparityFileError(path + ": truncated at row " + std::to_string(height - 1 - v));
  }
  const bool file_little = scale < 0;
  if (file_little != host_is_little_endian()) {
    for (int v = 0; v < height; ++v) {
      auto* bytes = raw.ptr<uint8_t>(v);
      for (size_t i = 0; i < row_bytes; i += 4) {
        std::swap(bytes[i], bytes[i + 3]);
        std::swap(bytes[i + 1], bytes[i + 2]);
      }
    }
  }
  if (channels == 1) return raw;
  cv::Mat first;
  cv::extractChannel(raw, first, 0);
  return first;
}

void write_pfm(const std::string& path, const cv::Mat& disparity) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw DisparityFileError(path + ": cannot write");
  out << "Pf\n"
      << disparity.cols << " " << disparity.rows << "\n"
      << (host_is_little_endian() ? "-1.0" : "1.0") << "\n";
  for (int v = disparity.rows - 1; v >= 0; --v)
    out.write(reinterpret_cast<const char*>(disparity.ptr<float>(v)),
              static_cast<std::streamsize>(static_cast<size_t>(disparity.cols) * sizeof(float)));
}

cv::Mat load_disparity(const std::string& path, double divisor) {
  if (!(divisor > 0)) throw DisparityFileError("disparity divisor must be positive");
  if (!std::filesystem::exists(path)) throw DisparityFileError(path + ": no such file");
  cv::Mat disparity;
  const std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  if (ext == ".pfm" || ext == ".PFM") {
    disparity = read_pfm(path) / divisor;
  } else {
    const cv::Mat image = read_image(path, cv::IMREAD_UNCHANGED);
    if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
      throw DisparityFileError(path + ": a disparity PNG must have one 8- or 16-bit channel");
    image.convertTo(disparity, CV_32F, 1.0 / divisor);
  }
  mark_unknown(disparity);
  return disparity;
}

cv::Mat scale_disparity(const cv::Mat& disparity, double scale) {
  if (scale == 1.0) return disparity.clone();
  cv::Mat out;
  const cv::Size size(static_cast<int>(std::lround(disparity.cols * scale)),
                      static_cast<int>(std::lround(disparity.rows * scale)));
  cv::resize(disparity, out, size, 0, 0, cv::INTER_NEAREST);
  return out * scale;
}

}  // namespace ivoa::stereo_eval
