#include "ivoa/core/process.hpp"

#include <algorithm>
#include <fstream>
#include <iostream>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
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
      ->group("Channels");
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

// CLI11 says "INI was not able to parse KEY" of a --config key that names no
// option; say which file and what to check.
void explain_config_error(const CLI::App& app, const CLI::ConfigError& e) {
  const std::string prefix = "INI was not able to parse ";
  const std::string what = e.what();
  const CLI::Option* config = app.get_config_ptr();
  const std::string file = config && !config->results().empty() ? config->results().back() : std::string();
  if (what.rfind(prefix, 0) == 0)
    std::cerr << "--config " << file << ": '" << what.substr(prefix.size())
              << "' is not an option of this program (see --help)\n";
  else std::cerr << "--config " << file << ": " << what << "\n";
}

// A bad value from a --config file: CLI11 names the option ("--mc-passes:
// must be a number"), not where the value came from. Names the file when the
// option is not on the command line.
void explain_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  const CLI::Option* config = app.get_config_ptr();
  const std::string what = e.what();
  const std::string option = what.substr(0, what.find(':'));
  const bool on_command_line =
      std::any_of(argv + 1, argv + argc, [&](const char* a) { return std::string(a).rfind(option, 0) == 0; });
  if (config && !config->results().empty() && option.rfind("--", 0) == 0 && !on_command_line &&
      (dynamic_cast<const CLI::ValidationError*>(&e) || dynamic_cast<const CLI::ConversionError*>(&e)))
    std::cerr << "--config " << config->results().back() << ": " << what << "\n";
  else app.exit(e);
}

}  // namespace

int parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ConfigError& e) {
    explain_config_error(app, e);
    return kExitUsage;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? kExitOk : kExitUsage;  // --help
    explain_parse_error(app, e, argc, argv);
    return kExitUsage;
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
  std::ofstream out(path);
  // Flushed here: a full disk fails the flush, not the buffered <<.
  if (out << text << std::flush) return true;
  spdlog::error("cannot write {}", path);
  return false;
}

bool write_ready_file(const std::string& path) { return write_text_file(path, "ready\n"); }

}  // namespace ivoa
