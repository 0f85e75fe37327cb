#include "ivoa/core/channel_counts.hpp"

#include <cerrno>
#include <cstdlib>
#include <stdexcept>

namespace ivoa {

std::map<std::string, int64_t> parse_channel_counts(const std::vector<std::string>& args, const std::string& option) {
  std::map<std::string, int64_t> counts;
  for (const auto& arg : args) {
    const auto eq = arg.find('=');
    const std::string count = eq == std::string::npos ? "" : arg.substr(eq + 1);
    char* end = nullptr;
    errno = 0;
    const long long n = count.empty() ? -1 : std::strtoll(count.c_str(), &end, 10);
    if (eq == 0 || count.empty() || *end != '\0' || errno == ERANGE || n < 0)
      throw std::invalid_argument((option.empty() ? "" : option + " ") + arg +
                                  ": use CHANNEL=N, N a whole number of messages");
    if (const auto [it, added] = counts.emplace(arg.substr(0, eq), n); !added)  // the last silently won
      throw std::invalid_argument((option.empty() ? "" : option + " ") + it->first +
                                  " is given twice (=" + std::to_string(it->second) + " and =" + count + ")");
  }
  return counts;
}

}  // namespace ivoa
