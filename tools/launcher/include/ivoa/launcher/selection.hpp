#pragma once
// Which commands of a configuration this launcher runs: those for its host
// (a command without host/deputy runs on "localhost"), in the chosen
// groups, minus skipped commands or groups, with variables expanded.
#include <string>
#include <vector>

#include "ivoa/launcher/config.hpp"
#include "ivoa/launcher/supervisor.hpp"
#include "ivoa/launcher/variables.hpp"

namespace ivoa::launcher {

inline constexpr const char* kDefaultHost = "localhost";
inline constexpr const char* kAnyHost = "*";

struct Selection {
  std::string host = kDefaultHost;  // kAnyHost: every command
  std::vector<std::string> groups;  // empty: all
  std::vector<std::string> skip;    // command or group names
};

struct SelectedCommands {
  std::vector<LaunchCommand> commands;
  std::vector<std::string> other_hosts;  // "name (host)" of commands left to other machines
};

// Throws ConfigError for a group or skip name the file does not have, and
// (with the command's file:line) for a variable without a value.
SelectedCommands select_commands(const Config& config, const Selection& selection, const Variables& variables);

// The host a command runs on.
std::string host_of(const CommandSpec& command);

}  // namespace ivoa::launcher
