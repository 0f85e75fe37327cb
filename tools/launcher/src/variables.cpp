#include "ivoa/launcher/variables.hpp"

#include <cctype>
#include <cstdlib>
#include <stdexcept>

namespace ivoa::launcher {
namespace {

// Deep enough for defaults built on defaults; a cycle stops here.
constexpr int kMaxDepth = 16;
// An exec string is one argument of sh -c: Linux takes at most 128 kB.
// Defaults that repeat each other stop here, not when memory runs out.
constexpr size_t kMaxExpandedBytes = 1 << 20;

bool valid_name(const std::string& name) {
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_')) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

}  // namespace

std::optional<std::string> process_environment(const std::string& name) {
  const char* v = std::getenv(name.c_str());
  if (!v) return std::nullopt;
  return std::string(v);
}

Variables::Variables(const Config& config, std::map<std::string, std::string> overrides,
                     std::map<std::string, std::string> builtins, EnvironmentLookup environment)
    : overrides_(std::move(overrides)), builtins_(std::move(builtins)), environment_(std::move(environment)) {
  for (const auto& [name, d] : config.defaults) defaults_[name] = d.value;
}

std::optional<std::string> Variables::raw_value(const std::string& name, bool& expandable) const {
  expandable = true;
  if (auto it = overrides_.find(name); it != overrides_.end()) return it->second;
  if (auto v = environment_(name)) {
    expandable = false;  // the environment's values are taken as they are
    return v;
  }
  if (auto it = defaults_.find(name); it != defaults_.end()) return it->second;
  if (auto it = builtins_.find(name); it != builtins_.end()) return it->second;
  return std::nullopt;
}

std::string Variables::expand_depth(const std::string& text, const std::string& where, int depth) const {
  if (depth > kMaxDepth) throw ConfigError(where + ": variables refer to each other in a cycle");
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 2, "${") != 0) {
      out += text[i];
      continue;
    }
    const auto close = text.find('}', i + 2);
    if (close == std::string::npos) throw ConfigError(where + ": '${' without a closing '}'");
    const std::string name = text.substr(i + 2, close - i - 2);
    if (!valid_name(name))
      throw ConfigError(where + ": '${" + name + "}' is not a variable name (letters, digits, '_')");
    bool expandable = true;
    const auto v = raw_value(name, expandable);
    if (!v)
      throw ConfigError(where + ": variable ${" + name + "} is not set (use --set " + name +
                        "=VALUE, export it, or add '# @default " + name + " = VALUE' to the file)");
    out += expandable ? expand_depth(*v, where + " (in ${" + name + "})", depth + 1) : *v;
    if (out.size() > kMaxExpandedBytes)
      throw ConfigError(where + ": expands to more than " + std::to_string(kMaxExpandedBytes >> 20) +
                        " MB (variables that repeat each other?)");
    i = close;
  }
  return out;
}

std::string Variables::expand(const std::string& text, const std::string& where) const {
  return expand_depth(text, where, 0);
}

std::optional<std::string> Variables::value(const std::string& name) const {
  bool expandable = true;
  const auto v = raw_value(name, expandable);
  if (!v || !expandable) return v;
  return expand(*v, "${" + name + "}");
}

std::set<std::string> variables_of(const Config& config) {
  std::set<std::string> names;
  const auto add_used = [&](const std::string& text) {
    for (size_t open = text.find("${"); open != std::string::npos; open = text.find("${", open + 2)) {
      const size_t close = text.find('}', open + 2);
      if (close == std::string::npos) return;
      names.insert(text.substr(open + 2, close - open - 2));
    }
  };
  for (const auto& c : config.commands) add_used(c.exec);
  for (const auto& [name, d] : config.defaults) {
    names.insert(name);
    add_used(d.value);
  }
  return names;
}

std::map<std::string, std::string> Variables::exported() const {
  std::map<std::string, std::string> out;
  for (const auto* source : {&builtins_, &defaults_, &overrides_})
    for (const auto& [name, raw] : *source) {
      try {
        const auto v = value(name);
        if (v && environment_(name) != v) out[name] = *v;
      } catch (const ConfigError&) {
        // A default built on an unset variable: no command can use it either
        // (expand() reports it where one does).
      }
    }
  return out;
}

std::pair<std::string, std::string> parse_assignment(const std::string& text) {
  const auto eq = text.find('=');
  const std::string name = text.substr(0, eq);
  if (eq == std::string::npos || !valid_name(name)) throw std::invalid_argument("'" + text + "' is not NAME=VALUE");
  return {name, text.substr(eq + 1)};
}

}  // namespace ivoa::launcher
