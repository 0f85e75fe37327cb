#include "ivoa/launcher/selection.hpp"

#include <algorithm>

namespace ivoa::launcher {
namespace {

bool in_any_group(const CommandSpec& c, const std::vector<std::string>& groups) {
  return std::any_of(groups.begin(), groups.end(), [&](const std::string& g) { return in_group(c, g); });
}

void check_names(const Config& config, const Selection& selection) {
  for (const auto& g : selection.groups)
    if (!config.has_group(g)) throw ConfigError(config.path + ": no group \"" + g + "\" (--group)");
  for (const auto& s : selection.skip)
    if (!config.has_group(s) && !config.find_command(s))
      throw ConfigError(config.path + ": no command or group \"" + s + "\" (--skip)");
}

}  // namespace

std::string host_of(const CommandSpec& command) { return command.host.empty() ? kDefaultHost : command.host; }

SelectedCommands select_commands(const Config& config, const Selection& selection, const Variables& variables) {
  check_names(config, selection);
  SelectedCommands out;
  for (const auto& c : config.commands) {
    if (!selection.groups.empty() && !in_any_group(c, selection.groups)) continue;
    if (std::find(selection.skip.begin(), selection.skip.end(), c.name) != selection.skip.end() ||
        in_any_group(c, selection.skip))
      continue;
    if (selection.host != kAnyHost && host_of(c) != selection.host) {
      out.other_hosts.push_back(c.name + " (" + host_of(c) + ")");
      continue;
    }
    LaunchCommand launch{
        c, variables.expand(c.exec, config.path + ":" + std::to_string(c.line) + ": cmd \"" + c.name + "\"")};
    out.commands.push_back(std::move(launch));
  }
  return out;
}

}  // namespace ivoa::launcher
