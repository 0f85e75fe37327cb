#pragma once
// A procman sheriff configuration (the subset in reference/lcm_notes.md §3):
// commands in (nested) groups, and scripts. The same files load in real
// procman; ivoa-launch reads them without a deputy/sheriff pair.
//
//   group "1.perception" {
//       cmd "stereo_detector" {
//           exec = "${IVOA_BIN}/ivoa-stereo-detector --model jppc";
//           host = "localhost";        # or deputy = "..."
//           auto_respawn = "true";
//           stop_signal = 2;           # default SIGINT
//           stop_time_allowed = 7;     # seconds before SIGKILL
//       }
//   }
//   script "start" { start group "1.perception" wait "running"; wait ms 500; }
//
// Variable defaults for ivoa-launch live in comments, invisible to procman:
//   # @default SEED = 1
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace ivoa::launcher {

// A syntax or meaning error; what() is "FILE:LINE: message".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kDefaultStopSignal = 2;             // SIGINT, as procman
inline constexpr double kDefaultStopTimeAllowedS = 7.0;  // as procman

struct CommandSpec {
  std::string name;
  std::string group;  // "a/b" for nested groups, "" at top level
  std::string exec;   // as written, before variable expansion
  std::string host;   // "" if the file names none
  bool auto_respawn = false;
  int stop_signal = kDefaultStopSignal;
  double stop_time_allowed_s = kDefaultStopTimeAllowedS;
  int line = 0;
};

enum class StepAction { kStart, kStop, kRestart, kWaitMs, kWaitStatus, kRunScript };
enum class TargetKind { kCommand, kGroup, kEverything };

struct ScriptStep {
  StepAction action = StepAction::kStart;
  TargetKind target_kind = TargetKind::kEverything;
  std::string target;       // command or group name, or script name for kRunScript
  std::string wait_status;  // "running" or "stopped"; "" = do not wait
  double wait_ms = 0;
  int line = 0;
};

struct ScriptSpec {
  std::string name;
  std::vector<ScriptStep> steps;
  int line = 0;
};

struct VariableDefault {
  std::string value;
  int line = 0;
};

struct Config {
  std::string path;
  std::vector<CommandSpec> commands;
  std::vector<std::string> groups;  // every group path, in file order
  std::vector<ScriptSpec> scripts;
  std::map<std::string, VariableDefault> defaults;
  std::vector<std::string> warnings;  // "FILE:LINE: ..." for attributes procman knows and we ignore

  const CommandSpec* find_command(const std::string& name) const;
  const ScriptSpec* find_script(const std::string& name) const;
  bool has_group(const std::string& path) const;
};

// Parses config text; `path` names the file in error messages.
Config parse_config(const std::string& text, const std::string& path);
// Reads and parses a file; an unreadable file is a ConfigError too.
Config load_config(const std::string& path);

// True if the command is in `group` or one of its subgroups.
bool in_group(const CommandSpec& command, const std::string& group);

// A script with every run_script inlined, in execution order. Throws
// ConfigError (naming the line) for unknown scripts, commands or groups and
// for scripts that run themselves.
std::vector<ScriptStep> flatten_script(const Config& config, const std::string& name);

}  // namespace ivoa::launcher
