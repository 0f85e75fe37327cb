#include "ivoa/core/disk_space.hpp"

#include <unistd.h>

#include <filesystem>
#include <system_error>

namespace ivoa {

std::optional<uint64_t> free_bytes_for(const std::string& file) {
  std::filesystem::path folder = std::filesystem::path(file).parent_path();
  if (folder.empty()) folder = ".";
  std::error_code error;
  const auto space = std::filesystem::space(folder, error);
  if (error) return std::nullopt;
  return static_cast<uint64_t>(geteuid() == 0 ? space.free : space.available);
}

}  // namespace ivoa
