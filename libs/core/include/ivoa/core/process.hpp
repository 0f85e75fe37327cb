#pragma once
// What every executable shares: logging set up one way, common flags
// (LCM URL, log level, config file), meaningful exit codes, and the loop
// that handles LCM until SIGINT/SIGTERM.
#include <functional>
#include <string>
#include <vector>

#include "ivoa/core/channels.hpp"

namespace CLI {
class App;
}

namespace ivoa {
class Bus;
class Heartbeat;

// Exit codes (documented in the README).
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,   // runtime failure (LCM, device, ...)
  kExitUsage = 2,     // bad flags or config
  kExitBadInput = 3,  // an input file is unusable (calibration, log, model)
  kExitIoError = 4,   // cannot write output (disk full, permissions)
};

struct CommonOptions {
  std::string lcm_url;  // empty = default_lcm_url()
  std::string log_level = "info";
  std::string status_channel{channels::kProcessStatus};  // for add_status_channel_option
};

// Adds --lcm-url, --log-level and --config (a TOML/INI file that sets any
// flag by its long name, e.g. `conf_pos_thresh = 0.75`).
void add_common_options(CLI::App& app, CommonOptions& options);

// For tools that talk no LCM: --log-level and --config only, so that an
// --lcm-url is refused rather than accepted and ignored.
void add_offline_options(CLI::App& app, CommonOptions& options);

// The environment variable that, when set, replaces PROCESS_STATUS as every
// program's heartbeat channel; ivoa-launch sets it in its commands'
// environment to its own --status-channel, as it sets LCM_DEFAULT_URL to a
// udpm --lcm-url, so that a launched stack reports where the launcher listens.
inline constexpr const char* kStatusChannelEnv = "IVOA_STATUS_CHANNEL";

// --status-channel, in the "Channels" group: where a process publishes its
// heartbeat (`channel` holds the default, channels::kProcessStatus). The flag,
// then a --config file's `status-channel`, then $IVOA_STATUS_CHANNEL decide.
void add_status_channel_option(CLI::App& app, std::string& channel);

// Parses argv; on --help or a usage error prints and returns the exit code
// to use, otherwise returns -1 and the caller continues.
int parse_command_line(CLI::App& app, int argc, char** argv);

// Writes `text` to `path` (nothing if `path` is empty), for outputs such as
// --json. False, with an error naming the file logged, if it cannot be written.
bool write_text_file(const std::string& path, const std::string& text);

// Why `path` could not be written ("is a folder", "No such file or
// directory"), or "" if it can (or is empty). Probes by opening it to
// append, leaving no file behind that was not there: outputs written only
// at the end of a long run are checked at its start.
std::string why_cannot_write(const std::string& path);

// The one of `files` that is the existing file `path` (the same device and
// inode, whatever the spelling), or "": an output about to be written over
// one of a tool's inputs (`--json run.lcmlog.0*` in a shell) is refused.
std::string same_file_among(const std::string& path, const std::vector<std::string>& files);

// The first of `files` that is an earlier one again (by any name, as
// same_file_among sees it), or "": an input given twice would count twice.
std::string file_given_twice(const std::vector<std::string>& files);

// Whether writing `path` would write over `input`: the same file (by any
// spelling, also before either exists), or an existing file inside the
// folder `input` (a dataset, a folder of scene files); a new file there
// writes over nothing.
bool writes_over(const std::string& path, const std::string& input);

// Whether `path` is `folder` or lies inside it, as spelt or resolved,
// whether or not `path` exists yet (an output that must stay out of an
// input folder).
bool lies_within(const std::string& path, const std::string& folder);

// Why `path` cannot be read as a file ("no such file", "is a folder", "is a
// pipe, device or socket, not a file"), or "" if it is a regular file: a
// reader that opened a named pipe would wait for a writer for ever.
std::string why_not_a_file(const std::string& path);

// --ready-file: creates `path` (nothing if empty) to tell a waiting script
// that this process has subscribed or is serving (write_text_file).
bool write_ready_file(const std::string& path);

// Sets up spdlog (stderr, one pattern for every process).
void init_logging(const std::string& process_name, const std::string& level);

// Handles LCM until a stop is requested, calling `periodic` (if any) and
// heartbeat.tick() at least every `poll_ms`. Returns kExitFailure if LCM
// fails, kExitOk otherwise; with `stop_at_end_of_log` an end of a file://
// log also ends the loop normally.
int run_until_stopped(Bus& bus, Heartbeat* heartbeat, const std::function<void()>& periodic = {}, int poll_ms = 50,
                      bool stop_at_end_of_log = false);

}  // namespace ivoa
