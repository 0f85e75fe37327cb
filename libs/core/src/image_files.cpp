#include "ivoa/core/image_files.hpp"

#include <filesystem>
#include <string_view>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "ivoa/core/atomic_files.hpp"

namespace ivoa {

std::string image_file_name_problem(const std::string& path) {
  const std::filesystem::path file(path);
  if (file.extension().empty() || !cv::haveImageWriter(path))
    return path + ": no image format for the name (use .png or .jpg)";
  const std::filesystem::path folder = file.parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder))
    return path + ": there is no folder " + folder.string();
  return "";
}

bool write_image_file(const std::string& path, const cv::Mat& image, std::string& error) {
  error = image_file_name_problem(path);
  if (!error.empty()) return false;
  const std::string extension = std::filesystem::path(path).extension().string();
  std::vector<uchar> bytes;
  try {
    if (!cv::imencode(extension, image, bytes)) throw cv::Exception(0, "no encoder", "imencode", __FILE__, __LINE__);
  } catch (const cv::Exception& e) {
    error = path + ": cannot encode the image as " + extension + " (" + e.err + ")";
    return false;
  }
  return replace_file(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), error);
}

}  // namespace ivoa
