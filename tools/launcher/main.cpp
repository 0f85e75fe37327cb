// ivoa-launch: runs a procman configuration (procman_configs/*.pmd) on this
// machine, without procman: the commands for --host, each in its own
// process group, output prefixed "[name] ", auto_respawn with back-off, a
// clean stop on Ctrl-C/SIGTERM, and a status table with each process's
// PROCESS_STATUS heartbeat.
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include <CLI/CLI.hpp>
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/launcher/config.hpp"
#include "ivoa/launcher/group_watchdog.hpp"
#include "ivoa/launcher/launcher.hpp"
#include "ivoa/launcher/selection.hpp"
#include "ivoa/launcher/variables.hpp"

namespace fs = std::filesystem;
using namespace ivoa::launcher;

namespace {

struct CliOptions {
  std::string config_path;
  Selection selection;
  std::vector<std::string> sets;
  bool list = false;
  bool plain = false;
  LauncherOptions launcher;
};

// Times in seconds up to a year: beyond, std::chrono's nanoseconds overflow.
const CLI::Validator kSeconds = ivoa::number_in(0.0, 365 * 86400.0);

void add_options(CLI::App& app, CliOptions& o) {
  auto& l = o.launcher;
  app.add_option("file", o.config_path, "procman configuration (.pmd)")->required()->check(CLI::ExistingFile);
  app.add_option("--host", o.selection.host, "run the commands for this host (host/deputy); '*' = all")
      ->capture_default_str();
  app.add_option("--group,-g", o.selection.groups, "only the commands in these groups (\"a/b\" for nested)");
  app.add_option("--skip", o.selection.skip, "leave out these commands or groups");
  app.add_option("--set", o.sets,
                 "NAME=VALUE for ${NAME} (before the environment and the file's defaults; the last of a name wins; "
                 "IVOA_STATUS_CHANNEL and a udpm:// LCM_DEFAULT_URL are --status-channel's and --lcm-url's)");
  app.add_option("--script", l.script, "run this script of the file instead of starting every command");
  app.add_option("--stop-script", l.stop_script,
                 "at the stop, run this script of the file first if it has one (the producers before the logger), "
                 "then stop what still runs; \"\" = stop everything at once")
      ->capture_default_str();
  app.add_option("--duration", l.duration_s, "stop everything after this many seconds (0: no limit)")->check(kSeconds);
  app.add_flag("--once", l.once, "stop everything once every command without auto_respawn has ended");
  app.add_option("--until", l.until, "stop everything once these commands have ended");
  app.add_option("--grace", l.grace_s, "seconds the others keep running after --once/--until holds")
      ->capture_default_str()
      ->check(kSeconds);
  app.add_option("--status-file", l.status_file,
                 "write the final status here (JSON if it ends in .json, else the table)");
  app.add_option("--status-every", l.status_every_s,
                 "print the table every S seconds when not on a terminal (0: at the end only)")
      ->capture_default_str()
      ->check(kSeconds);
  app.add_flag("--plain", o.plain, "on a terminal too: prefixed lines and a periodic table instead of a live table");
  app.add_option("--output-dir", l.output_dir, "also append each command's output to DIR/NAME.log");
  app.add_option("--status-channel", l.status_channel,
                 "heartbeat channel: the status table and `wait \"running\"` read it, the launcher publishes its "
                 "own there, and its commands get it as $IVOA_STATUS_CHANNEL")
      ->capture_default_str()
      ->envname(ivoa::kStatusChannelEnv);
  app.add_option("--ready-timeout", l.ready_timeout_s,
                 "a script's wait \"running\" on an ivoa program waits for its first heartbeat at most this long, "
                 "s (0: not at all)")
      ->capture_default_str()
      ->check(kSeconds);
  app.add_flag("--list", o.list,
               "print the commands that would run, expanded, and what it adds to their environment; exit");
  const char* g = "Respawn";
  auto& s = l.supervisor;
  app.add_option("--respawn-delay", s.respawn_delay_s, "first back-off, s (doubles while it keeps failing)")
      ->capture_default_str()
      ->group(g)
      ->check(kSeconds);
  app.add_option("--respawn-max-delay", s.respawn_max_delay_s, "longest back-off, s")
      ->capture_default_str()
      ->group(g)
      ->check(kSeconds);
  app.add_option("--healthy-after", s.healthy_after_s, "a run this long resets the back-off, s")
      ->capture_default_str()
      ->group(g)
      ->check(kSeconds);
}

// IVOA_BIN: where ivoa-launch itself is (build/bin: every executable);
// IVOA_CONFIG_DIR: the configuration's folder.
std::map<std::string, std::string> builtin_variables(const std::string& config_path) {
  std::map<std::string, std::string> out;
  char exe[PATH_MAX] = {0};
  if (readlink("/proc/self/exe", exe, sizeof(exe) - 1) > 0) out["IVOA_BIN"] = fs::path(exe).parent_path().string();
  out["IVOA_CONFIG_DIR"] = fs::absolute(config_path).parent_path().lexically_normal().string();
  return out;
}

void print_commands(const SelectedCommands& selected, const LauncherOptions& l) {
  for (const auto& c : selected.commands)
    std::printf("%s%s%s%s\n    %s\n", c.spec.name.c_str(),
                c.spec.group.empty() ? "" : (" [" + c.spec.group + "]").c_str(),
                c.spec.auto_respawn ? " auto_respawn" : "",
                (" stop_signal " + std::to_string(c.spec.stop_signal)).c_str(), c.shell_command.c_str());
  for (const auto& o : selected.other_hosts) std::printf("(other host) %s\n", o.c_str());
  std::printf("in every command's environment:");
  for (const auto& [name, value] : bus_environment(l)) std::printf(" %s=%s", name.c_str(), value.c_str());
  std::printf("\n");
}

const char* flag_that_sets(const std::string& bus_variable) {
  return bus_variable == ivoa::kStatusChannelEnv ? "--status-channel" : "--lcm-url";
}

// --set NAME=VALUE (the last of a name wins), and the bus settings the
// commands get (bus_environment) as strong, so that ${IVOA_STATUS_CHANNEL}
// in an exec string is what a command gets as $IVOA_STATUS_CHANNEL. A --set
// or a file's default that contradicts them would leave the status table
// empty: the one is refused, the other ignored with a warning, each naming
// the flag to use instead.
std::map<std::string, std::string> variable_overrides(const CliOptions& o, const Config& config) {
  const auto bus = bus_environment(o.launcher);
  const std::set<std::string> used = variables_of(config);
  std::map<std::string, std::string> overrides;
  for (const auto& s : o.sets) {
    auto [name, value] = parse_assignment(s);
    if (const auto b = bus.find(name); b != bus.end() && b->second != value)
      throw ConfigError("--set " + s + ": the launcher hands its commands " + name + "=" + b->second + " (" +
                        flag_that_sets(name) + "); change it there");
    if (!bus.count(name) && !config.defaults.count(name) && !used.count(name))
      spdlog::warn("--set {}: {} has no ${{{}}} (its variables: {}); it only reaches the commands' environment", s,
                   config.path, name, fmt::join(used, ", "));
    overrides[name] = value;
  }
  for (const auto& [name, value] : bus) {
    if (const auto d = config.defaults.find(name); d != config.defaults.end() && d->second.value != value)
      spdlog::warn("{}:{}: the default {} = {} is not used: the launcher hands its commands {}={} ({})", config.path,
                   d->second.line, name, d->second.value, name, value, flag_that_sets(name));
    overrides[name] = value;
  }
  return overrides;
}

// A built-in the environment sets otherwise (an IVOA_BIN exported for
// another build) wins over the launcher's own; said, since the commands
// then run other binaries than the launcher's.
void warn_of_builtins_from_the_environment(const std::map<std::string, std::string>& builtins,
                                           const std::map<std::string, std::string>& overrides) {
  for (const auto& [name, own] : builtins) {
    const char* exported = std::getenv(name.c_str());
    std::error_code error;
    if (exported && !fs::equivalent(own, exported, error) && !overrides.count(name))
      spdlog::warn(
          "{}={} from the environment, not this launcher's {}: the commands use it (unset {} to use the "
          "launcher's)",
          name, exported, own, name);
  }
}

// Loads the configuration and picks this host's commands; throws with the
// file and line of what is wrong.
SelectedCommands prepare(CliOptions& o, Config& config) {
  config = load_config(o.config_path);
  for (const auto& w : config.warnings) spdlog::warn("{}", w);
  const std::map<std::string, std::string> builtins = builtin_variables(o.config_path);
  std::map<std::string, std::string> overrides = variable_overrides(o, config);
  warn_of_builtins_from_the_environment(builtins, overrides);
  const Variables variables(config, std::move(overrides), builtins);
  SelectedCommands selected = select_commands(config, o.selection, variables);
  o.launcher.supervisor.environment = variables.exported();
  if (!o.launcher.script.empty()) flatten_script(config, o.launcher.script);
  if (o.launcher.stop_script != LauncherOptions().stop_script && !o.launcher.stop_script.empty() &&
      !config.find_script(o.launcher.stop_script))
    throw ConfigError(config.path + ": --stop-script " + o.launcher.stop_script + ": no such script");
  for (const auto& name : o.launcher.until) {
    const bool selected_here = std::any_of(selected.commands.begin(), selected.commands.end(),
                                           [&](const LaunchCommand& c) { return c.spec.name == name; });
    if (!selected_here) throw ConfigError(config.path + ": --until " + name + ": no such command runs here");
  }
  return selected;
}

// --output-dir and --status-file are written during and after the run:
// a path that cannot be is found out before anything starts. "" if fine.
std::string output_path_problem(const LauncherOptions& l) {
  if (!l.output_dir.empty()) {
    std::error_code error;
    fs::create_directories(l.output_dir, error);
    if (error || !fs::is_directory(l.output_dir))
      return "--output-dir " + l.output_dir + ": cannot create the folder" +
             (error ? ": " + error.message() : " (a file of that name exists)");
  }
  if (const std::string why = ivoa::why_cannot_write(l.status_file); !why.empty())
    return "--status-file " + l.status_file + ": cannot write: " + why;
  return "";
}

// False (with the hosts the configuration has) if nothing runs on this host.
bool something_to_run(const Config& config, const SelectedCommands& selected, const CliOptions& o) {
  if (!selected.other_hosts.empty())
    spdlog::info("{} command(s) for other hosts not run here (--host {})", selected.other_hosts.size(),
                 o.selection.host);
  if (selected.commands.empty()) {
    std::set<std::string> hosts;
    for (const auto& c : config.commands) hosts.insert(host_of(c));
    spdlog::error("{}: no command to run for host '{}' (its hosts: {}; pass --host NAME, or --host '*' for all)",
                  config.path, o.selection.host, fmt::join(hosts, ", "));
    return false;
  }
  if (o.launcher.once && std::all_of(selected.commands.begin(), selected.commands.end(),
                                     [](const LaunchCommand& c) { return c.spec.auto_respawn; }))
    spdlog::warn("--once: every command respawns, so only --duration or a signal ends the run");
  return true;
}

// The commands get the launcher's bus settings with the variables
// (variable_overrides); an --lcm-url they cannot share is said so.
void warn_of_an_lcm_url_not_handed_on(const LauncherOptions& l) {
  if (!l.lcm_url.empty() && l.lcm_url != "none" && l.lcm_url.rfind("udpm://", 0) != 0)
    spdlog::warn(
        "--lcm-url {}: the commands do not get it (they would each have a bus of their own), so their "
        "heartbeats reach the status table only if they publish there",
        l.lcm_url);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Run a procman configuration (.pmd) on this machine: the commands for --host, respawned when they die, "
      "stopped cleanly on Ctrl-C; PROCESS_STATUS heartbeats in the status table (--lcm-url none: without LCM). "
      "Exit codes: 0 ok, 1 a command without auto_respawn failed, 2 bad flags or configuration, 4 --output-dir "
      "or --status-file cannot be written."};
  ivoa::CommonOptions common;
  CliOptions o;
  ivoa::add_common_options(app, common);
  add_options(app, o);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("launcher", common.log_level);
  o.launcher.lcm_url = common.lcm_url;

  Config config;
  SelectedCommands selected;
  try {
    selected = prepare(o, config);
    warn_of_an_lcm_url_not_handed_on(o.launcher);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  if (const std::string problem = o.list ? "" : output_path_problem(o.launcher); !problem.empty()) {
    spdlog::error("{}", problem);
    return ivoa::kExitIoError;
  }
  if (o.list) {
    print_commands(selected, o.launcher);
    return ivoa::kExitOk;
  }
  if (!something_to_run(config, selected, o)) return ivoa::kExitUsage;
  o.launcher.redraw = !o.plain && isatty(STDOUT_FILENO);
  // Orphans of the commands come to us, so a command's group can be seen to empty.
  prctl(PR_SET_CHILD_SUBREAPER, 1);
  o.launcher.supervisor.reap_orphans = true;
  // Forked before anything else runs: it stops what we leave running if we are killed.
  GroupWatchdog watchdog(argc, argv);
  if (!watchdog.running()) spdlog::warn("no watchdog: if ivoa-launch is killed, compound commands' children run on");
  o.launcher.supervisor.on_group_started = [&](int pgid, const CommandSpec& spec) {
    watchdog.watch(pgid, spec.stop_signal, spec.stop_time_allowed_s);
  };
  o.launcher.supervisor.on_group_gone = [&](int pgid) { watchdog.forget(pgid); };
  install_launcher_signal_handlers();
  try {
    return run_launcher(config, std::move(selected.commands), o.selection.host, o.launcher);
  } catch (const std::exception& e) {
    // The supervisor has SIGKILLed the commands on its way out: say why.
    spdlog::error("{}", e.what());
    return ivoa::kExitFailure;
  }
}
