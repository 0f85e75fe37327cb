#include "ivoa/core/file_names.hpp"

#include <filesystem>

namespace ivoa {

std::string numbered_file_name(const std::string& path, int n) {
  if (n == 0) return path;
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "-" + std::to_string(n) + p.extension().string())).string();
}

std::optional<std::string> first_free_numbered_name(const std::string& path, int max_suffix,
                                                    const std::function<bool(const std::string&)>& take) {
  for (int n = 0; n <= max_suffix; ++n) {
    const std::string name = numbered_file_name(path, n);
    if (take(name)) return name;
  }
  return std::nullopt;
}

}  // namespace ivoa
