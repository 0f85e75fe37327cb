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

// The offset after the entropy-coded data that starts at `i`: at the next
// marker (FF, then neither a stuffed 00 nor a restart D0-D7), or the end.
size_t skip_scan_data(const std::string& d, size_t i) {
  while (i + 1 < d.size()) {
    const auto next = static_cast<unsigned char>(d[i + 1]);
    if (static_cast<unsigned char>(d[i]) == 0xFF && next != 0x00 && (next < 0xD0 || next > 0xD7)) return i;
    ++i;
  }
  return d.size();
}

// Walks a JPEG's segments from its start (skipping what they hold, so an
// EXIF thumbnail's own end marker does not count) to the end-of-image marker
// FF D9; what follows it (phones append data) does not matter. A file whose
// structure is not a JPEG's is left to OpenCV.
bool jpeg_cut_short(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string d((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto byte = [&d](size_t i) { return static_cast<unsigned char>(d[i]); };
  if (d.size() < 2 || byte(0) != 0xFF || byte(1) != 0xD8) return false;
  size_t i = 2;
  while (i + 1 < d.size()) {
    if (byte(i) != 0xFF) return false;  // not a segment boundary: not ours to judge
    const unsigned char marker = byte(i + 1);
    if (marker == 0xD9) return false;  // the end of the image: whole
    if (marker == 0xFF || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      i += marker == 0xFF ? 1 : 2;  // fill byte, or a marker without a length
      continue;
    }
    if (i + 3 >= d.size()) return true;
    i += 2 + (static_cast<size_t>(byte(i + 2)) << 8 | byte(i + 3));
    if (i > d.size()) return true;  // the segment runs past the end
    if (marker == 0xDA) i = skip_scan_data(d, i);
  }
  return true;  // no end-of-image marker
}

}  // namespace

cv::Mat read_image(const std::string& path, int imread_flags) {
  if (!std::filesystem::exists(path)) throw DisparityFileError(path + ": no such file");
  if (std::filesystem::is_directory(path)) throw DisparityFileError(path + ": a folder, not an image");
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
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(channels) * sizeof(float);
  // The header's size against what the file holds, before allocating it (a damaged header can ask for petabytes).
  const auto header_end = static_cast<uint64_t>(in.tellg());
  const uint64_t file_bytes = std::filesystem::file_size(path);
  const uint64_t data_bytes = file_bytes > header_end ? file_bytes - header_end : 0;
  if (static_cast<double>(row_bytes) * height > static_cast<double>(data_bytes))
    throw DisparityFileError(path + ": its header says " + std::to_string(width) + "x" + std::to_string(height) +
                             " but the file holds " + std::to_string(data_bytes) + " bytes of data (truncated?)");
  cv::Mat raw(height, width, CV_32FC(channels));
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
  if (std::filesystem::is_directory(path)) throw DisparityFileError(path + ": a folder, not an image");
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
