#include "ivoa/logio/session_name.hpp"

#include <cctype>
#include <filesystem>

namespace ivoa::logio {

std::string session_name_of(const std::string& log_path) {
  std::string name = std::filesystem::path(log_path).filename().string();
  const auto dot = name.rfind('.');
  if (dot != std::string::npos && name.size() - dot == 3 && std::isdigit(static_cast<unsigned char>(name[dot + 1])) &&
      std::isdigit(static_cast<unsigned char>(name[dot + 2])))
    name = name.substr(0, dot);
  for (const std::string ext : {".lcmlog", ".lcm", ".log"})
    if (name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0)
      name = name.substr(0, name.size() - ext.size());
  return name;
}

}  // namespace ivoa::logio
