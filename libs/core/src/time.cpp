#include "ivoa/core/time.hpp"

#include <ctime>

namespace ivoa {

std::string expand_time_pattern(const std::string& pattern) {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  std::string out(4096, '\0');
  out.resize(std::strftime(out.data(), out.size(), pattern.c_str(), &local));
  return out;
}

}  // namespace ivoa
