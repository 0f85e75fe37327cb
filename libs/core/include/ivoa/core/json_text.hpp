#pragma once
// Writing JSON by hand (sidecars, status files, metadata): a string as a
// JSON string literal, quotes, backslashes and control characters escaped.
#include <string>
#include <string_view>

namespace ivoa {

std::string json_quote(std::string_view text);

}  // namespace ivoa
