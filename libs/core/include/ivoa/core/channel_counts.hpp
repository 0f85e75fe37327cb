#pragma once
// "CHANNEL=N" arguments: message counts expected per channel (the --expect of
// ivoa-lcm-stats and ivoa-log-check).
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace ivoa {

// Throws std::invalid_argument naming `option` (if not empty) and the
// argument that is not CHANNEL=N, with a channel and N a whole number >= 0.
std::map<std::string, int64_t> parse_channel_counts(const std::vector<std::string>& args, const std::string& option);

}  // namespace ivoa
