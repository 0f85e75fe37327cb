#include "ivoa/launcher/launcher.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

#include <spdlog/spdlog.h>

#include "heartbeat_monitor.hpp"
#include "readiness_gate.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/launcher/script_runner.hpp"
#include "ivoa/launcher/status_report.hpp"

namespace ivoa::launcher {
namespace {

using Clock = std::chrono::steady_clock;

std::atomic<int> g_stop_signals{0};
std::atomic<int> g_last_signal{0};
extern "C" void on_launcher_stop_signal(int sig) {
  g_last_signal.store(sig);
  g_stop_signals.fetch_add(1);
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A command's name as a file name in --output-dir: a '/' would reach into
// (or, with "..", out of) other folders.
std::string file_name_for(std::string command_name) {
  std::replace(command_name.begin(), command_name.end(), '/', '_');
  return command_name;
}

// Where command output goes: "[name] line" on stdout (or, while a live
// table is drawn, the last lines under it), and optionally one file per command.
class OutputPrinter {
 public:
  OutputPrinter(const LauncherOptions& options, const std::vector<std::string>& names) : redraw_(options.redraw) {
    if (options.output_dir.empty()) return;
    std::filesystem::create_directories(options.output_dir);
    for (const auto& n : names) {
      const std::string path = options.output_dir + "/" + file_name_for(n) + ".log";
      files_[n].open(path, std::ios::app);
      if (!files_[n]) spdlog::warn("[{}] cannot write its output to {}: {}", n, path, std::strerror(errno));
    }
  }

  void line(const std::string& name, const std::string& text) {
    std::string prefixed = "[" + name + "] " + text;
    if (auto it = files_.find(name); it != files_.end()) it->second << text << '\n' << std::flush;
    if (redraw_) {
      tail_.push_back(std::move(prefixed));
      if (tail_.size() > kTailLines) tail_.pop_front();
    } else {
      prefixed += '\n';
      std::fwrite(prefixed.data(), 1, prefixed.size(), stdout);
      std::fflush(stdout);
    }
  }

  void event(const std::string& name, const std::string& text) {
    if (auto it = files_.find(name); it != files_.end()) it->second << "[launcher] " << text << '\n' << std::flush;
    line("launcher", name + ": " + text);
  }

  // The table on its own (periodic) or a full screen: header, table, newest lines.
  void show(const std::string& header, const std::string& table) {
    if (!redraw_) {
      std::printf("%s\n%s", header.c_str(), table.c_str());
      std::fflush(stdout);
      return;
    }
    winsize ws{};
    const int rows = ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_row > 0 ? ws.ws_row : 40;
    const size_t cols = ws.ws_col > 0 ? ws.ws_col : 160;
    std::string screen = "\x1b[H\x1b[J" + header + "\n" + table + std::string(std::min<size_t>(cols, 100), '-') + "\n";
    const int used = 3 + static_cast<int>(std::count(table.begin(), table.end(), '\n'));
    const size_t room = static_cast<size_t>(std::max(0, rows - used));
    for (size_t i = tail_.size() > room ? tail_.size() - room : 0; i < tail_.size(); ++i)
      screen += tail_[i].substr(0, cols) + "\n";
    std::fwrite(screen.data(), 1, screen.size(), stdout);
    std::fflush(stdout);
  }

  // After the live table: the screen is left as it is and lines print normally.
  void end_redraw() { redraw_ = false; }

 private:
  static constexpr size_t kTailLines = 500;
  bool redraw_;
  std::deque<std::string> tail_;
  std::map<std::string, std::ofstream> files_;
};

class Run {
 public:
  Run(const Config& config, std::vector<LaunchCommand> commands, const std::string& host,
      const LauncherOptions& options)
      : config_(config),
        host_(host),
        options_(options),
        printer_(options, names_of(commands)),
        readiness_(commands, options.ready_timeout_s, event_printer()),
        supervisor_(
            std::move(commands), options.supervisor,
            [this](const std::string& n, const std::string& l) { printer_.line(n, l); }, event_printer()) {
    connect_lcm();
    if (!options_.script.empty())
      script_ = std::make_unique<ScriptRunner>(flatten_script(config_, options_.script), supervisor_, event_printer(),
                                               [this](const std::string& name) { return announced(name); });
  }

  int run() {
    started_ = Clock::now();
    if (script_) script_->advance();
    else supervisor_.start_all();
    std::string reason;
    while ((reason = end_reason()).empty()) {
      const bool lcm_ready = supervisor_.step(100, monitor_ ? monitor_->fd() : -1);
      if (lcm_ready) monitor_->drain();
      if (script_) script_->advance();
      publish_own_heartbeat();
      show_periodically();
    }
    // The screen is left as it is; the stop's events print below it.
    printer_.end_redraw();
    printer_.event("all", "stopping (" + reason + ")");
    const int signals_before = g_stop_signals.load();
    bool killed = run_stop_script(signals_before);
    supervisor_.stop_all();
    while (supervisor_.busy()) {
      if (supervisor_.step(100, monitor_ ? monitor_->fd() : -1)) monitor_->drain();
      if (!killed) killed = kill_on_second_signal(signals_before);
    }
    if (monitor_) monitor_->drain();  // the heartbeats the commands sent as they stopped
    const int code = exit_code();
    printer_.show(header(false), format_status_table(rows()));
    write_status_file(reason, code);
    return code;
  }

 private:
  static std::vector<std::string> names_of(const std::vector<LaunchCommand>& commands) {
    std::vector<std::string> out;
    for (const auto& c : commands) out.push_back(c.spec.name);
    return out;
  }

  EventHandler event_printer() {
    return [this](const std::string& n, const std::string& e) { printer_.event(n, e); };
  }

  // The file's stop script, stepped like the start script; each of its
  // stops is bounded by the command's stop_time_allowed. A second stop
  // signal cuts it short and kills every command (returns true then).
  bool run_stop_script(int signals_before) {
    if (options_.stop_script.empty() || !config_.find_script(options_.stop_script)) return false;
    printer_.event("all", "running script \"" + options_.stop_script + "\"");
    ScriptRunner stop(flatten_script(config_, options_.stop_script), supervisor_, event_printer(),
                      [this](const std::string& name) { return announced(name); });
    for (stop.advance(); !stop.done(); stop.advance()) {
      if (supervisor_.step(100, monitor_ ? monitor_->fd() : -1)) monitor_->drain();
      if (kill_on_second_signal(signals_before)) return true;
    }
    return false;
  }

  // Once another stop signal has come since the stop began, kills every
  // command at once; true then.
  bool kill_on_second_signal(int signals_before) {
    if (g_stop_signals.load() <= signals_before) return false;
    printer_.event("all", "second stop signal: SIGKILL to every command");
    supervisor_.kill_all();
    return true;
  }

  // Without LCM there are no heartbeats to wait for.
  bool announced(const std::string& name) {
    return !monitor_ || readiness_.ready(supervisor_.status(name), monitor_->latest(name));
  }

  void connect_lcm() {
    if (options_.lcm_url == "none") return;
    try {
      bus_ = std::make_unique<Bus>(options_.lcm_url);
      monitor_ = std::make_unique<HeartbeatMonitor>(*bus_, options_.status_channel, supervisor_);
      own_heartbeat_ = std::make_unique<Heartbeat>(*bus_, "launcher", options_.status_channel);
      own_heartbeat_->set_state("running");
      // What is not a heartbeat on the status channel is counted, its warnings rate-limited, as every
      // process does (it was a warning a message).
      bus_->on_decode_error([this](const std::string& what) { own_heartbeat_->bad_input(what); });
    } catch (const BusError& e) {
      spdlog::warn("no LCM ({}): running without heartbeats", e.what());
      monitor_.reset();
      own_heartbeat_.reset();
      bus_.reset();
    }
  }

  bool ended(const std::string& name) const { return supervisor_.status(name).state == RunState::kStopped; }

  // The commands --once waits for: those without auto_respawn that were started.
  bool once_condition() const {
    bool any = false;
    for (const auto& s : supervisor_.statuses()) {
      if (s.auto_respawn || s.state == RunState::kIdle) continue;
      any = true;
      if (!ended(s.name)) return false;
    }
    return any && (!script_ || script_->done());
  }

  bool until_condition() const {
    for (const auto& name : options_.until)
      if (!ended(name)) return false;
    return !options_.until.empty();
  }

  std::string end_reason() {
    if (g_stop_signals.load() > 0) return "signal " + std::to_string(g_last_signal.load());
    if (options_.duration_s > 0 && seconds_since(started_) >= options_.duration_s) return "--duration reached";
    if (!supervisor_.busy() && (!script_ || script_->done())) return "every command has ended";
    const bool condition = (options_.once && once_condition()) || until_condition();
    if (!condition) {
      condition_since_.reset();
      return "";
    }
    if (!condition_since_) condition_since_ = Clock::now();
    if (seconds_since(*condition_since_) < options_.grace_s) return "";
    if (options_.once) return "--once: done";
    std::string ended_names;  // how they ended (a failure) is said as each ends
    for (const auto& name : options_.until) ended_names += (ended_names.empty() ? "" : ", ") + name;
    return "--until: " + ended_names + " ended";
  }

  std::vector<StatusRow> rows() const {
    std::vector<StatusRow> out;
    for (const auto& s : supervisor_.statuses()) {
      StatusRow row;
      row.command = s;
      if (monitor_)
        if (auto h = monitor_->latest(s.name)) {
          row.heartbeat = h->status;
          row.heartbeat_age_s = std::chrono::duration<double>(Clock::now() - h->received).count();
          row.earlier = h->earlier;
          const bool sender_runs =
              (s.state == RunState::kRunning || s.state == RunState::kStopping) && h->instance == s.pid;
          row.heartbeat_sender_ended = h->local && !sender_runs && h->status.state != "stopped";
        }
      out.push_back(std::move(row));
    }
    return out;
  }

  std::string header(bool live = true) const {
    char text[512];
    std::snprintf(text, sizeof(text), "ivoa-launch %s  host %s  %.0f s%s", config_.path.c_str(), host_.c_str(),
                  seconds_since(started_), live && options_.redraw ? "  (Ctrl-C stops everything)" : "");
    return text;
  }

  void show_periodically() {
    const double period = options_.redraw ? 1.0 : options_.status_every_s;
    if (period <= 0 || seconds_since(last_shown_) < period) return;
    last_shown_ = Clock::now();
    printer_.show(header(), format_status_table(rows()));
  }

  void publish_own_heartbeat() {
    if (!own_heartbeat_) return;
    int running = 0;
    const auto all = supervisor_.statuses();
    for (const auto& s : all) {
      running += s.state == RunState::kRunning;
      own_heartbeat_->set_counter(s.name + ".restarts", s.restarts);
    }
    own_heartbeat_->set_counter("running", running);
    own_heartbeat_->set_counter("commands", static_cast<int64_t>(all.size()));
    own_heartbeat_->tick();
  }

  int exit_code() const {
    int code = 0;
    for (const auto& s : supervisor_.statuses())
      if (!s.auto_respawn && s.failed) {
        spdlog::error(
            "{} failed ({})", s.name,
            s.exit_signal ? "signal " + std::to_string(s.exit_signal) : "exit code " + std::to_string(s.exit_code));
        code = 1;
      }
    return code;
  }

  void write_status_file(const std::string& reason, int code) const {
    if (options_.status_file.empty()) return;
    const auto& path = options_.status_file;
    const bool json = path.size() >= 5 && path.compare(path.size() - 5, 5, ".json") == 0;
    RunSummary summary{config_.path, host_, seconds_since(started_), reason, code};
    std::ofstream out(path);
    out << (json ? format_status_json(rows(), summary) : header(false) + "\n" + format_status_table(rows()));
    if (!out) spdlog::error("cannot write the status file {}", path);
  }

  const Config& config_;
  std::string host_;
  LauncherOptions options_;
  OutputPrinter printer_;
  ReadinessGate readiness_;
  Supervisor supervisor_;
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<HeartbeatMonitor> monitor_;
  std::unique_ptr<Heartbeat> own_heartbeat_;
  std::unique_ptr<ScriptRunner> script_;
  Clock::time_point started_, last_shown_ = Clock::now();
  std::optional<Clock::time_point> condition_since_;
};

}  // namespace

std::map<std::string, std::string> bus_environment(const LauncherOptions& options,
                                                   const EnvironmentLookup& environment) {
  std::map<std::string, std::string> handed{{kStatusChannelEnv, options.status_channel}};
  std::string url = options.lcm_url;
  if (url.empty()) url = environment("LCM_DEFAULT_URL").value_or("");
  if (url.empty()) url = kProjectDefaultUrl;  // what Bus("") listens on, less its receive buffer
  if (url.rfind("udpm://", 0) == 0) handed["LCM_DEFAULT_URL"] = url;
  return handed;
}

void install_launcher_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_launcher_stop_signal;
  sigemptyset(&action.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

int run_launcher(const Config& config, std::vector<LaunchCommand> commands, const std::string& host,
                 const LauncherOptions& options) {
  Run run(config, std::move(commands), host, options);
  return run.run();
}

}  // namespace ivoa::launcher
