#include "ivoa/logio/channel_filter.hpp"

#include <algorithm>
#include <stdexcept>

namespace ivoa::logio {
namespace {

std::regex compile(const std::string& pattern, const char* what) {
  try {
    return std::regex(pattern, std::regex::ECMAScript | std::regex::optimize);
  } catch (const std::regex_error& e) {
    throw std::invalid_argument(std::string(what) + " '" + pattern + "' is not a valid regex: " + e.what());
  }
}

}  // namespace

ChannelFilter::ChannelFilter(const std::string& include, const std::string& exclude, std::vector<std::string> always)
    : include_(compile(include, "--channels")),
      exclude_(compile(exclude.empty() ? "$^" : exclude, "--exclude")),
      has_exclude_(!exclude.empty()),
      always_(std::move(always)) {}

bool ChannelFilter::accepts(const std::string& channel) {
  const auto it = decisions_.find(channel);
  if (it != decisions_.end()) return it->second;
  const bool accepted = decide(channel);
  decisions_.emplace(channel, accepted);
  return accepted;
}

bool ChannelFilter::decide(const std::string& channel) const {
  if (std::find(always_.begin(), always_.end(), channel) != always_.end()) return true;
  if (!std::regex_match(channel, include_)) return false;
  return !(has_exclude_ && std::regex_match(channel, exclude_));
}

}  // namespace ivoa::logio
