#pragma once
// Image files (figures, overlays, galleries) written whole, or a reason why not.
#include <string>

#include <opencv2/core.hpp>

namespace ivoa {

// Encodes `image` in the format its name's extension says (.png, .jpg, ...)
// and replaces `path` whole (replace_file). On failure: false, and `error`
// names the file and why (no format for the extension, no such folder,
// permissions, a full disk).
bool write_image_file(const std::string& path, const cv::Mat& image, std::string& error);

// What makes `path` unusable before anything is rendered: an extension with
// no image format, or a folder that is not there; "" if neither.
std::string image_file_name_problem(const std::string& path);

}  // namespace ivoa
