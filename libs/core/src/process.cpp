#include "ivoa/core/process.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/stop_signal.hpp"

namespace ivoa {

void add_common_options(CLI::App& app, CommonOptions& options) {
  app.add_option(
      "--lcm-url", options.lcm_url,
      "LCM URL (default: $LCM_DEFAULT_URL or " + std::string(kProjectDefaultUrl) + ", with a 16 MB receive buffer)");
  add_offline_options(app, options);
}

void add_status_channel_option(CLI::App& app, std::string& channel) {
  app.add_option("--status-channel", channel, "out: heartbeat (ivoa.process_status_t)")
      ->capture_default_str()
      ->envname(kStatusChannelEnv)
      ->group("Channels")
      ->check(ivoa::channel_name());
}

void add_offline_options(CLI::App& app, CommonOptions& options) {
  app.add_option("--log-level", options.log_level, "trace, debug, info, warn, error")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  app.set_config("--config", "", "TOML/INI file setting any option by its long name");
  // A misspelt key would otherwise be dropped without a word, and the
  // process run with the default it meant to change.
  app.allow_config_extras(CLI::config_extras_mode::error);
}

namespace {

// The --config file given, or "".
std::string config_file(const CLI::App& app) {
  const CLI::Option* config = app.get_config_ptr();
  return config && !config->results().empty() ? config->results().back() : std::string();
}

// CLI11 says "INI was not able to parse KEY" of a --config key that names no
// option; say which file and what to check.
void explain_config_error(const CLI::App& app, const CLI::ConfigError& e) {
  const std::string prefix = "INI was not able to parse ";
  const std::string what = e.what();
  const std::string file = config_file(app);
  if (what.rfind(prefix, 0) == 0)
    std::cerr << "--config " << file << ": '" << what.substr(prefix.size())
              << "' is not an option of this program (see --help)\n";
  else std::cerr << "--config " << file << ": " << what << "\n";
}

// The option a CLI11 error is about: "NAME: why" or "Could not convert: NAME = value".
std::string option_in_error(const std::string& what) {
  const std::string convert = "Could not convert: ";
  if (what.rfind(convert, 0) == 0) return what.substr(convert.size(), what.find(" = ") - convert.size());
  return what.substr(0, what.find(':'));
}

// The option by that name in the app or a subcommand the command line chose.
const CLI::Option* find_option(const CLI::App& app, const std::string& name) {
  if (const CLI::Option* o = app.get_option_no_throw(name)) return o;
  for (const CLI::App* sub : app.get_subcommands())
    if (const CLI::Option* o = find_option(*sub, name)) return o;
  return nullptr;
}

// True if the command line gives the option by any of its names.
bool on_command_line(const CLI::Option& option, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    for (const auto& l : option.get_lnames())
      if (a == "--" + l || a.rfind("--" + l + "=", 0) == 0) return true;
    for (const auto& s : option.get_snames())
      if (a.rfind("-" + s, 0) == 0 && a.rfind("--", 0) != 0) return true;
  }
  return false;
}

// True if the configuration file, read as CLI11 reads it, sets the option by one of its long names.
bool config_sets(const CLI::App& app, const std::string& file, const CLI::Option& option) {
  try {
    for (const CLI::ConfigItem& item : app.get_config_formatter()->from_file(file))
      for (const auto& name : option.get_lnames())
        if (item.name == name) return true;
  } catch (const CLI::Error&) {
  }
  return false;
}

// A bad value from a --config file: CLI11 names the option ("--mc-passes:
// must be a number"), not where the value came from. Names the file when
// the file sets the option and the command line does not (a positional one
// is left as it is: its value may have come from either).
void explain_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  const std::string file = config_file(app), what = e.what();
  const CLI::Option* option = find_option(app, option_in_error(what));
  if (!file.empty() && option && !option->get_positional() && !on_command_line(*option, argc, argv) &&
      config_sets(app, file, *option))
    std::cerr << "--config " << file << ": " << what << "\n";
  else app.exit(e);
}

// CLI11 checks for required options before unknown ones, so a misspelt
// flag was reported as the option it left unset ("--out is required" for
// `build --bogus`). The unknown arguments are named first.
bool explain_unknown_arguments(const CLI::App& app, const CLI::ParseError& e) {
  if (e.get_name() != "RequiredError" || app.get_allow_extras()) return false;
  const std::vector<std::string> unknown = app.remaining(true);
  if (unknown.empty()) return false;
  std::string list;
  for (const auto& arg : unknown) list += (list.empty() ? "" : " ") + arg;
  std::cerr << "unknown argument" << (unknown.size() == 1 ? "" : "s") << ": " << list << " (and " << e.what()
            << ")\nRun with --help for more information.\n";
  return true;
}

// An offline tool (no --lcm-url of its own) given one: CLI11 took its value
// for a file to read ("logs: File does not exist: udpm://...").
bool refuse_an_lcm_url_offline(const CLI::App& app, int argc, char** argv) {
  if (app.get_option_no_throw("--lcm-url")) return false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--") break;
    if (arg == "--lcm-url" || arg.rfind("--lcm-url=", 0) == 0) {
      std::cerr << "--lcm-url: " << std::filesystem::path(argv[0]).filename().string()
                << " reads files and talks no LCM: give the logs as arguments\n";
      return true;
    }
  }
  return false;
}

}  // namespace

int parse_command_line(CLI::App& app, int argc, char** argv) {
  if (refuse_an_lcm_url_offline(app, argc, argv)) return kExitUsage;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ConfigError& e) {
    explain_config_error(app, e);
    return kExitUsage;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? kExitOk : kExitUsage;  // --help
    if (explain_unknown_arguments(app, e)) return kExitUsage;
    explain_parse_error(app, e, argc, argv);
    return is_missing_input(e) ? kExitBadInput : kExitUsage;
  }
  return -1;
}

void init_logging(const std::string& process_name, const std::string& level) {
  auto logger = spdlog::stderr_color_mt(process_name);
  logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %^%-5l%$ [%n] %v");
  logger->set_level(spdlog::level::from_str(level));
  spdlog::set_default_logger(logger);
}

int run_until_stopped(Bus& bus, Heartbeat* heartbeat, const std::function<void()>& periodic, int poll_ms,
                      bool stop_at_end_of_log) {
  install_stop_handlers();
  while (!stop_requested()) {
    const int r = bus.handle(poll_ms);
    if (r < 0) {
      // A stop signal interrupts LCM's wait (EINTR): that is a stop, not a failure.
      if (stop_requested() || stop_at_end_of_log) break;
      spdlog::error("LCM handle failed on '{}'", bus.url());
      return kExitFailure;
    }
    if (periodic) periodic();
    if (heartbeat) heartbeat->tick();
  }
  if (heartbeat) {
    heartbeat->set_state("stopped");
    heartbeat->publish_now();
  }
  return kExitOk;
}

bool write_text_file(const std::string& path, const std::string& text) {
  if (path.empty()) return true;
  std::error_code no_file;
  const auto type = std::filesystem::status(path, no_file).type();
  if (type != std::filesystem::file_type::regular && type != std::filesystem::file_type::not_found) {
    errno = 0;  // /dev/stdout, a pipe: written through, not replaced
    std::ofstream out(path);
    // Flushed here: a full disk fails the flush, not the buffered <<.
    if (out << text << std::flush) return true;
    spdlog::error("cannot write {}{}", path, errno != 0 ? std::string(": ") + std::strerror(errno) : "");
    return false;
  }
  // Replaced whole: a full disk left a cut or empty file where the last
  // run's results had been.
  std::string error;
  if (replace_file(path, text, error)) return true;
  spdlog::error("cannot write {}", error);
  return false;
}

std::string why_cannot_write(const std::string& path) {
  if (path.empty()) return "";
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return "is a folder";
  const bool existed = std::filesystem::exists(path, error);
  errno = 0;
  std::ofstream probe(path, std::ios::app);
  if (!probe) return errno != 0 ? std::strerror(errno) : "cannot be opened";
  probe.close();
  if (!existed) std::filesystem::remove(path, error);
  return "";
}

std::string same_file_among(const std::string& path, const std::vector<std::string>& files) {
  struct stat out {};
  if (path.empty() || ::stat(path.c_str(), &out) != 0) return "";
  for (const auto& file : files) {
    struct stat in {};
    if (::stat(file.c_str(), &in) == 0 && in.st_dev == out.st_dev && in.st_ino == out.st_ino) return file;
  }
  return "";
}

std::string file_given_twice(const std::vector<std::string>& files) {
  for (size_t i = 1; i < files.size(); ++i)
    if (!same_file_among(files[i], {files.begin(), files.begin() + static_cast<std::ptrdiff_t>(i)}).empty())
      return files[i];
  return "";
}

namespace {

// `inner` is `outer` or below it, both normal absolute paths.
bool is_under(const std::filesystem::path& inner, const std::filesystem::path& outer) {
  const auto relative = inner.lexically_relative(outer);  // "../x" when outside
  return !relative.empty() && *relative.begin() != "..";
}

// `path` absolute and as spelt, but for what its last ".." steps up from: a
// ".." after a link leaves the link's target, not the folder it is spelt
// in, so the part up to it is resolved and the rest kept as written.
std::filesystem::path as_spelt(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path absolute = fs::absolute(path);
  fs::path up_to_last_up, rest;
  for (const auto& part : absolute) {
    rest /= part;
    if (part == "..") {
      up_to_last_up /= rest;
      rest.clear();
    }
  }
  if (up_to_last_up.empty()) return absolute.lexically_normal();
  std::error_code error;
  const fs::path resolved = fs::weakly_canonical(up_to_last_up, error);
  return error ? fs::path() : (resolved / rest).lexically_normal();  // empty: lies within nothing
}

}  // namespace

bool writes_over(const std::string& path, const std::string& input) {
  if (path.empty() || input.empty()) return false;
  if (!same_file_among(path, {input}).empty()) return true;
  std::error_code error;
  // Absolute first: a relative path none of whose folders exists stays relative.
  const auto out = std::filesystem::weakly_canonical(std::filesystem::absolute(path), error);
  const auto in = std::filesystem::weakly_canonical(std::filesystem::absolute(input), error);
  if (error) return false;
  if (out == in) return true;
  if (!std::filesystem::is_directory(in, error) || !std::filesystem::exists(out, error)) return false;
  return is_under(out, in);
}

bool lies_within(const std::string& path, const std::string& folder) {
  namespace fs = std::filesystem;
  // as spelt, too: through a folder inside that is a link, the resolved path leaves `folder`
  if (is_under(as_spelt(path), as_spelt(folder))) return true;
  std::error_code error;
  const auto inner = fs::weakly_canonical(fs::absolute(path), error);
  const auto outer = fs::weakly_canonical(fs::absolute(folder), error);
  return !error && is_under(inner, outer);
}

std::string why_not_a_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return errno == ENOENT ? "no such file" : std::strerror(errno);
  if (S_ISDIR(st.st_mode)) return "is a folder, not a file";
  if (!S_ISREG(st.st_mode)) return "is a pipe, device or socket, not a file";
  return "";
}

bool write_ready_file(const std::string& path) { return write_text_file(path, "ready\n"); }

}  // namespace ivoa
