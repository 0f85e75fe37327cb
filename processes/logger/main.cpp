// ivoa-logger: records LCM traffic into standard LCM log files (replay them
// with lcm-logplayer, browse them with lcm-spy). Unlike lcm-logger 1.3.1 it
// writes out everything it received before exiting on SIGINT, SIGTERM or SIGHUP,
// counts what it could not keep if the disk is too slow, and on a write
// error leaves a readable file and exits with code 4.
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/file_names.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/logger/recorder.hpp"
#include "ivoa/logger/split_log.hpp"

namespace {

using ivoa::logger::Recorder;
using ivoa::logger::RecorderOptions;
using ivoa::logger::RecorderStatus;
using ivoa::logger::SplitLog;
using ivoa::logger::SplitLogOptions;

// Messages LCM had already taken in when the stop came are still handled,
// within this bound (traffic may go on arriving).
constexpr int kFinalHandleLimit = 2000;
constexpr double kFinalHandleMs = 500;
constexpr double kStatusPeriodMs = 100;  // recorder totals -> heartbeat counters
constexpr double kDrainReportMs = 2000;
constexpr int kMaxLogSuffix = 999;  // --increment: FILE-1 ... FILE-999
constexpr double kMaxMb = 1e9;      // sizes and rates in MB: a petabyte (bytes fit in 64 bits)

std::string hostname() {
  char buf[256] = {0};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

double mb(int64_t bytes) { return static_cast<double>(bytes) / 1e6; }

// Heartbeat counters are increments; the recorder keeps totals.
class StatusReporter {
 public:
  explicit StatusReporter(ivoa::Heartbeat& heartbeat) : heartbeat_(heartbeat) {}
  void update(const RecorderStatus& s, const std::string& state) {
    heartbeat_.count_in(s.received - last_.received);
    heartbeat_.count_out(s.written - last_.written);
    heartbeat_.count_dropped(s.dropped - last_.dropped);
    last_ = s;
    heartbeat_.set_counter("bytes_written", s.bytes_written);
    heartbeat_.set_counter("dropped_bytes", s.dropped_bytes);
    heartbeat_.set_counter("queue_depth", s.queue_depth);
    heartbeat_.set_counter("queue_bytes", s.queue_bytes);
    heartbeat_.set_counter("peak_queue_bytes", s.peak_queue_bytes);
    heartbeat_.set_counter("files", s.files);
    heartbeat_.set_counter("deleted", s.deleted);
    heartbeat_.set_counter("unwritten", s.unwritten);
    heartbeat_.set_state(state);
  }

 private:
  ivoa::Heartbeat& heartbeat_;
  RecorderStatus last_;
};

void handle_what_lcm_already_has(ivoa::Bus& bus) {
  const double until = ivoa::monotonic_ms() + kFinalHandleMs;
  for (int i = 0; i < kFinalHandleLimit && ivoa::monotonic_ms() < until; ++i)
    if (bus.handle(0) <= 0) break;
}

// `filter`: the --channels and --exclude regexes, named when nothing matched.
int report_end(const Recorder& recorder, double seconds, const std::string& filter) {
  const RecorderStatus s = recorder.status();
  if (s.received == 0) spdlog::warn("nothing was recorded: no message arrived on a channel matching {}", filter);
  std::string files;
  for (const auto& f : recorder.files()) files += (files.empty() ? "" : ", ") + f;
  spdlog::info("received {}, written {}, dropped {}; {:.1f} MB in {:.1f} s ({:.1f} MB/s), queue peak {:.1f} MB; {}",
               s.received, s.written, s.dropped, mb(s.bytes_written), seconds,
               seconds > 0 ? mb(s.bytes_written) / seconds : 0.0, mb(s.peak_queue_bytes), files);
  if (s.deleted > 0) spdlog::error("LOST {} messages written to a log file deleted while recording", s.deleted);
  if (s.failed) {
    const bool a_log_is_left = !recorder.files().empty() && std::filesystem::exists(recorder.files().back());
    spdlog::error(
        "{}; {} messages received were not written. {}", s.error, s.unwritten,
        a_log_is_left ? "The log ends with the last whole event and is readable." : "No log file of this run is left.");
    return ivoa::kExitIoError;
  }
  if (s.dropped > 0)
    spdlog::error(
        "LOST {} messages ({:.1f} MB) because the disk could not keep up (raise --max-queue-mb or use a "
        "faster disk)",
        s.dropped, mb(s.dropped_bytes));
  // A recording with holes is not a success, though what it holds is readable.
  return s.dropped > 0 || s.deleted > 0 ? ivoa::kExitIoError : ivoa::kExitOk;
}

// Handles LCM until a stop, the end of a file:// input or a write error.
int receive(ivoa::Bus& bus, Recorder& recorder, StatusReporter& reporter, ivoa::Heartbeat& heartbeat) {
  const bool reading_a_log = bus.reads_a_log();
  double next_status_ms = 0;
  while (!ivoa::stop_requested() && !recorder.failed()) {
    if (bus.handle(50) < 0) {
      // A stop signal can interrupt LCM's wait; a file:// input ends.
      if (ivoa::stop_requested() || reading_a_log) break;
      spdlog::error("LCM handle failed on '{}'", bus.url());
      return ivoa::kExitFailure;
    }
    if (ivoa::monotonic_ms() >= next_status_ms) {
      reporter.update(recorder.status(), recorder.check_health());
      next_status_ms = ivoa::monotonic_ms() + kStatusPeriodMs;
    }
    heartbeat.tick();
  }
  return ivoa::kExitOk;
}

// Waits while the writer empties the queue, at full speed (--max-write-mb-s
// no longer holds), keeping heartbeat and log informed.
void drain(Recorder& recorder, StatusReporter& reporter, ivoa::Heartbeat& heartbeat) {
  recorder.lift_write_cap();
  RecorderStatus s = recorder.status();
  spdlog::info("stopping: writing the {} queued messages ({:.1f} MB) to disk", s.queue_depth, mb(s.queue_bytes));
  double next_report_ms = ivoa::monotonic_ms() + kDrainReportMs;
  while (s.queue_depth > 0 && !s.failed) {
    reporter.update(s, "draining");
    heartbeat.tick();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    s = recorder.status();
    if (ivoa::monotonic_ms() < next_report_ms) continue;
    spdlog::info("draining: {} messages ({:.1f} MB) left", s.queue_depth, mb(s.queue_bytes));
    next_report_ms += kDrainReportMs;
  }
}

std::unique_ptr<Recorder> start_recorder(RecorderOptions options, int& exit_code) {
  try {
    const auto parent = std::filesystem::path(options.log.path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    return std::make_unique<Recorder>(std::move(options));
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    exit_code = ivoa::kExitUsage;
  } catch (const std::exception& e) {  // LogWriteError, filesystem_error
    spdlog::error("{}", e.what());
    exit_code = ivoa::kExitIoError;
  }
  return nullptr;
}

int record(const ivoa::CommonOptions& common, RecorderOptions options, const std::string& ready_file,
           double socket_buffer_mb) {
  std::unique_ptr<ivoa::Bus> bus;
  try {
    ivoa::logio::refuse_a_log_lcm_cannot_replay(common.lcm_url);
    bus = std::make_unique<ivoa::Bus>(common.lcm_url);
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
  options.log.identity.lcm_url = bus->url();
  const std::string filter = "--channels '" + options.channels + "'" +
                             (options.exclude.empty() ? "" : " and not --exclude '" + options.exclude + "'");
  int code = ivoa::kExitOk;
  const std::unique_ptr<Recorder> recorder = start_recorder(std::move(options), code);
  if (!recorder) return code;
  ivoa::Heartbeat heartbeat(*bus, "logger", common.status_channel);
  StatusReporter reporter(heartbeat);
  bus->subscribe_raw(".*", [&](const void* data, size_t size, const ivoa::ReceiveInfo& info) {
    recorder->on_message(info.channel, info.recv_utime, data, size);
  });
  ivoa::enlarge_receive_buffer(*bus, socket_buffer_mb);
  ivoa::write_ready_file(ready_file);  // a script may wait in vain, but recording goes on

  const double start_ms = ivoa::monotonic_ms();
  code = receive(*bus, *recorder, reporter, heartbeat);
  if (!recorder->failed()) {
    if (ivoa::stop_requested()) handle_what_lcm_already_has(*bus);
    drain(*recorder, reporter, heartbeat);
  }
  recorder->finish();
  const int end_code = report_end(*recorder, (ivoa::monotonic_ms() - start_ms) / 1000.0, filter);
  const RecorderStatus s = recorder->status();
  reporter.update(s, end_code == ivoa::kExitOk ? "stopped" : "error: " + s.error);
  heartbeat.publish_now();
  return code != ivoa::kExitOk ? code : end_code;
}

// The flags, in the units a user types (MB, MB/s); RecorderOptions holds bytes.
struct LoggerFlags {
  std::string file = "ivoa-%Y%m%d-%H%M%S.lcmlog", ready_file;
  double split_mb = 0, max_queue_mb = 1024, max_write_mb_s = 0, min_free_mb = 1000,
         socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
  bool force = false, increment = false, no_sidecar = false;
  RecorderOptions options;
};

void add_logger_options(CLI::App& app, LoggerFlags& f) {
  app.add_option("file", f.file, "log file name; strftime patterns (%Y, %H, ...) are expanded at start")
      ->capture_default_str();
  app.add_option("-c,--channels", f.options.channels, "record channels matching this regex (whole name)")
      ->capture_default_str();
  app.add_option("-x,--exclude", f.options.exclude,
                 "but not those matching this regex (the default skips the probe every LCM process sends at start)")
      ->capture_default_str();
  app.add_option("--split-mb", f.split_mb,
                 "start a new numbered file (FILE.00, FILE.01, ...) before one passes this size; 0 = never, else at "
                 "least 1")
      ->check(ivoa::number_in(0.0, kMaxMb));
  app.add_option("--calibration-channel", f.options.log.calibration_channel,
                 "always recorded, and copied to the start of every split file so each is self-contained "
                 "(empty: none)")
      ->capture_default_str();
  app.add_option("--max-queue-mb", f.max_queue_mb,
                 "memory for messages waiting for the disk; beyond it new ones are "
                 "dropped and counted")
      ->capture_default_str()
      ->check((ivoa::positive_number() & ivoa::number_in(0.0, kMaxMb)).description("NUMBER in (0, 1e+09]"));
  app.add_option("--max-write-mb-s", f.max_write_mb_s,
                 "cap the disk write rate while recording (0 = none; a stop "
                 "writes the queue out at full speed)")
      ->check(ivoa::number_in(0.0, kMaxMb));
  app.add_option("--min-free-mb", f.min_free_mb,
                 "stop recording (exit 4) before an event would leave less than this free on the log's disk, and do "
                 "not start with less than a quarter more: the system needs it more than the log (0 = fill the "
                 "disk)")
      ->capture_default_str()
      ->check(ivoa::number_in(0.0, kMaxMb));
  ivoa::add_socket_buffer_option(app, f.socket_buffer_mb);
  auto* force = app.add_flag("-f,--force", f.force, "overwrite existing files");
  app.add_flag("-i,--increment", f.increment,
               "if FILE exists, record to FILE-1, FILE-2, ... (before the extension) instead of refusing; lets a "
               "respawned logger with a fixed name go on recording")
      ->excludes(force);
  app.add_flag("--no-sidecar", f.no_sidecar, "do not write FILE.json next to each log");
  app.add_option("--ready-file", f.ready_file, "create this file once subscribed (lets scripts start publishers)");
}

// --increment: the first of PATH, PATH-1, ... whose log (or first split
// part) does not exist yet; false if none of the first 999 is free.
bool pick_unused_name(SplitLogOptions& log) {
  const std::string wanted = log.path, wanted_first_file = SplitLog::part_path(log, 0);
  SplitLogOptions candidate_log = log;
  const auto name = ivoa::first_free_numbered_name(wanted, kMaxLogSuffix, [&](const std::string& candidate) {
    candidate_log.path = candidate;
    return !std::filesystem::exists(SplitLog::part_path(candidate_log, 0));
  });
  if (!name) {
    spdlog::error(
        "{} and {} numbered variants exist; name the log with a time pattern such as "
        "ivoa-%Y%m%d-%H%M%S.lcmlog",
        wanted, kMaxLogSuffix);
    return false;
  }
  if (*name != wanted) spdlog::warn("{} exists (a log is never overwritten): logging to {}", wanted_first_file, *name);
  log.path = *name;
  return true;
}

// The recorder's options from the flags; false if the file name pattern
// expands to nothing or --increment finds no unused name.
bool fill_recorder_options(LoggerFlags& f) {
  RecorderOptions& o = f.options;
  o.log.path = ivoa::expand_time_pattern(f.file);
  if (o.log.path.empty()) {
    spdlog::error("the file name pattern '{}' expands to nothing", f.file);
    return false;
  }
  if (f.split_mb > 0 && f.split_mb < 1) {
    // A split file must hold the calibration and at least one stereo frame.
    spdlog::error("--split-mb: must be 0 (one file) or at least 1, not {}", f.split_mb);
    return false;
  }
  o.log.split_bytes = static_cast<uint64_t>(f.split_mb * 1e6);
  if (f.increment && !pick_unused_name(o.log)) return false;
  o.log.overwrite = f.force;
  o.log.sidecars = !f.no_sidecar;
  o.log.identity = {"ivoa-logger", IVOA_VERSION, IVOA_GIT_DESCRIBE, hostname(), "", o.channels, o.exclude};
  o.max_queue_bytes = static_cast<uint64_t>(f.max_queue_mb * 1e6);
  o.max_write_bytes_per_s = f.max_write_mb_s * 1e6;
  o.disk_reserve.min_free_bytes = static_cast<uint64_t>(f.min_free_mb * 1e6);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Record LCM channels into standard LCM log files (replay: lcm-logplayer; browse: lcm-spy).\n"
      "On SIGINT, SIGTERM or SIGHUP everything received is written before exiting. Exit codes: 0 ok, 1 LCM failure,\n"
      "2 bad flags, 3 a damaged file:// log to read, 4 the log could not be written, or not all of it (a write\n"
      "error, or --min-free-mb reached): messages were LOST (what was written stays readable)."};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  ivoa::add_status_channel_option(app, common.status_channel);
  LoggerFlags flags;
  add_logger_options(app, flags);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("logger", common.log_level);
  ivoa::install_stop_handlers();
  std::signal(SIGXFSZ, SIG_IGN);  // over a file size limit, write() fails with EFBIG instead
  if (!fill_recorder_options(flags)) return ivoa::kExitUsage;
  return record(common, std::move(flags.options), flags.ready_file, flags.socket_buffer_mb);
}
