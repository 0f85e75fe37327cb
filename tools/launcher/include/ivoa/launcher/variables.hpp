#pragma once
// ${NAME} variables in exec strings. Values come from, strongest first:
// --set NAME=VALUE, the launcher's environment, the configuration's
// "# @default NAME = VALUE" comments, and built-ins (IVOA_BIN: the folder
// of ivoa-launch; IVOA_CONFIG_DIR: the folder of the configuration file).
// Values from --set and defaults may themselves use ${OTHER}.
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "ivoa/launcher/config.hpp"

namespace ivoa::launcher {

using EnvironmentLookup = std::function<std::optional<std::string>(const std::string& name)>;
// The process environment (getenv).
std::optional<std::string> process_environment(const std::string& name);

class Variables {
 public:
  Variables(const Config& config, std::map<std::string, std::string> overrides,
            std::map<std::string, std::string> builtins, EnvironmentLookup environment = process_environment);

  // Replaces every ${NAME}. Throws ConfigError starting with `where` (e.g.
  // "sim.pmd:12") for a variable that has no value. "$NAME" without braces
  // is left to the shell, which sees the exported values.
  std::string expand(const std::string& text, const std::string& where) const;

  // The resolved value of one variable, if it has one.
  std::optional<std::string> value(const std::string& name) const;

  // Every variable the launcher knows a value for, except those already in
  // the environment unchanged: commands get them in theirs, so "$NAME"
  // inside a shell command agrees with ${NAME}.
  std::map<std::string, std::string> exported() const;

 private:
  std::optional<std::string> raw_value(const std::string& name, bool& expandable) const;
  std::string expand_depth(const std::string& text, const std::string& where, int depth) const;

  std::map<std::string, std::string> overrides_, defaults_, builtins_;
  EnvironmentLookup environment_;
};

// The variables a configuration knows: those it gives a default and those
// its exec strings and defaults use as ${NAME}.
std::set<std::string> variables_of(const Config& config);

// "NAME=VALUE" -> {NAME, VALUE}; throws std::invalid_argument otherwise.
std::pair<std::string, std::string> parse_assignment(const std::string& text);

}  // namespace ivoa::launcher
