// ivoa-lcm-stats: headless traffic statistics for LCM channels (what
// lcm-spy shows, for ssh sessions and CI). Can also wait for expected
// message counts and fail if they do not arrive.
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "channel_stats.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/bus.hpp"
#include "ivoa/logio/replay_check.hpp"
#include "ivoa/core/channel_counts.hpp"
#include "ivoa/core/message_registry.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/receive_buffer.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"

namespace {

int64_t count_on(const ivoa::tools::TrafficStats& stats, const std::string& channel) {
  const auto it = stats.channels().find(channel);
  return it == stats.channels().end() ? 0 : it->second.count;
}

bool expectations_met(const ivoa::tools::TrafficStats& stats, const std::map<std::string, int64_t>& expect) {
  for (const auto& [channel, n] : expect)
    if (count_on(stats, channel) < n) return false;
  return true;
}

// "CAMERA 3 of 10, DEPTH 0 of 5": the channels short of their count.
std::string shortfall(const ivoa::tools::TrafficStats& stats, const std::map<std::string, int64_t>& expect) {
  std::string out;
  for (const auto& [channel, n] : expect)
    if (const int64_t got = count_on(stats, channel); got < n)
      out += (out.empty() ? "" : ", ") + channel + " " + std::to_string(got) + " of " + std::to_string(n);
  return out;
}

struct Watch {
  std::string channels = ".*";
  double duration_s = 0, print_every_s = 2;
  std::string json_path, ready_file;
  std::map<std::string, int64_t> expect;
  double socket_buffer_mb = ivoa::kDefaultSocketBufferMb;
};

// Counts traffic until the expectations are met, the duration is over or a
// stop signal; prints the table as it goes and at the end.
int watch(const std::string& lcm_url, const Watch& w) {
  ivoa::logio::refuse_a_log_lcm_cannot_replay(lcm_url);
  ivoa::Bus bus(lcm_url);
  ivoa::tools::TrafficStats stats;
  try {
    bus.subscribe_raw(w.channels, [&](const void* data, size_t size, const ivoa::ReceiveInfo& info) {
      stats.add(info.channel, data, size, info.recv_utime);
    });
  } catch (const ivoa::BusError& e) {
    spdlog::error("--channels: {}", e.what());
    return ivoa::kExitUsage;
  }
  ivoa::install_stop_handlers();
  bus.handle(0);  // udpm joins the group lazily, on the first handle
  ivoa::enlarge_receive_buffer(bus, w.socket_buffer_mb);
  if (!ivoa::write_ready_file(w.ready_file)) return ivoa::kExitIoError;
  const double start = ivoa::monotonic_ms();
  double last_print = start;
  bool met = w.expect.empty();
  while (!ivoa::stop_requested()) {
    if (bus.handle(50) < 0) break;
    const double now = ivoa::monotonic_ms();
    if (!w.expect.empty() && expectations_met(stats, w.expect)) {
      met = true;
      break;
    }
    if (w.duration_s > 0 && now - start > w.duration_s * 1000.0) break;
    if (w.print_every_s > 0 && now - last_print > w.print_every_s * 1000.0) {
      std::printf("%s\n", stats.table().c_str());
      std::fflush(stdout);
      last_print = now;
    }
  }
  std::printf("%s", stats.table().c_str());
  if (!ivoa::write_text_file(w.json_path, stats.json())) return ivoa::kExitIoError;
  if (!met) {
    spdlog::error(
        "expected message counts did not arrive: {} (a channel --channels '{}' does not match is never "
        "counted)",
        shortfall(stats, w.expect), w.channels);
    return ivoa::kExitFailure;
  }
  return ivoa::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Per-channel LCM traffic: type, count, rate, bandwidth, sequence gaps"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  Watch w;
  std::vector<std::string> expect_args;
  bool list_types = false;
  app.add_option("--channels", w.channels, "channel regex (GLib syntax, matched against the whole name)")
      ->capture_default_str();
  app.add_option("--duration", w.duration_s, "stop after this many seconds (0 = until Ctrl-C)")
      ->check(ivoa::non_negative_number());
  app.add_option("--print-every", w.print_every_s, "print the table every N seconds (0 = only at the end)")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--json", w.json_path, "write the final statistics as JSON to this file");
  app.add_option("--expect", expect_args,
                 "CHANNEL=N (N >= 1): exit 0 as soon as every channel has N messages, 1 on timeout")
      ->delimiter(',');
  app.add_option("--ready-file", w.ready_file, "create this file once subscribed (lets scripts start publishers)");
  ivoa::add_socket_buffer_option(app, w.socket_buffer_mb);
  app.add_flag("--list-types", list_types, "print every ivoa message type and its fingerprint, then exit");
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("lcm-stats", common.log_level);
  try {
    w.expect = ivoa::parse_channel_counts(expect_args, "--expect");
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  for (const auto& [channel, n] : w.expect)
    if (n == 0) {
      spdlog::error("--expect {}=0: expect at least one message", channel);
      return ivoa::kExitUsage;
    }
  if (const std::string why = ivoa::why_cannot_write(w.json_path); !why.empty()) {
    spdlog::error("--json {}: cannot write: {}", w.json_path, why);
    return ivoa::kExitIoError;
  }
  if (list_types) {
    for (const auto& t : ivoa::message_types())
      std::printf("%s %lld\n", std::string(t.name).c_str(), static_cast<long long>(t.fingerprint));
    return ivoa::kExitOk;
  }
  try {
    return watch(common.lcm_url, w);
  } catch (const ivoa::BusError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}
