#include "ivoa/logio/session_name.hpp"

#include <cctype>
#include <filesystem>

namespace ivoa::logio {

bool is_split_part(const std::string& log_path) {
  const std::string ext = std::filesystem::path(log_path).extension().string();
  return ext.size() == 3 && std::isdigit(static_cast<unsigned char>(ext[1])) &&
         std::isdigit(static_cast<unsigned char>(ext[2]));
}

std::string split_parts_out_of_order(const std::vector<std::string>& logs) {
  namespace fs = std::filesystem;
  const auto recording = [](const std::string& log) {
    std::error_code error;  // a folder named through a link is the same folder
    const fs::path folder = fs::absolute(log).parent_path();
    const fs::path real = fs::weakly_canonical(folder, error);
    return (error ? folder.lexically_normal() : real) / fs::path(log).stem();
  };
  for (size_t i = 1; i < logs.size(); ++i) {
    const std::string &before = logs[i - 1], &log = logs[i];
    if (is_split_part(before) && is_split_part(log) && recording(before) == recording(log) &&
        fs::path(log).extension() < fs::path(before).extension())
      return log + " before " + before;
  }
  return "";
}

std::string session_name_of(const std::string& log_path) {
  std::string name = std::filesystem::path(log_path).filename().string();
  if (is_split_part(name)) name = name.substr(0, name.size() - 3);
  for (const std::string ext : {".lcmlog", ".lcm", ".log"})
    if (name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0)
      name = name.substr(0, name.size() - ext.size());
  return name;
}

}  // namespace ivoa::logio
