// ivoa-test-logger-helper: the small processes the logger's integration
// tests and benchmark need besides ivoa-test-publish.
//   publish: rig calibrations and messages on channels no ivoa type
//            describes (raw numbered bytes), at a rate;
//   wait:    until the logger's PROCESS_STATUS heartbeat shows a condition
//            (messages received, a counter's value), or fail on timeout.
#include <chrono>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/calibration.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"
#include "test_rig.hpp"

namespace {

struct PublishOptions {
  int calibrations = 5;
  int foreign = 5;
  std::vector<std::string> foreign_channels{"FOREIGN_DATA"};
  double rate_hz = 10;
};

// A payload no ivoa fingerprint matches: "FOREIGN!" then the number.
std::vector<uint8_t> foreign_payload(int i) {
  std::vector<uint8_t> bytes = {'F', 'O', 'R', 'E', 'I', 'G', 'N', '!'};
  for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(static_cast<uint8_t>(i >> shift));
  return bytes;
}

int publish(ivoa::Bus& bus, const PublishOptions& o) {
  const ivoa::RigCalibration rig = ivoa::test::make_test_rig();
  const auto period = std::chrono::duration<double>(1.0 / o.rate_hz);
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < std::max(o.calibrations, o.foreign); ++i) {
    if (i < o.calibrations) {
      ivoa::rig_calibration_t msg = ivoa::to_message(rig, ivoa::now_utime());
      if (!bus.publish(ivoa::channels::kRigCalibration, msg)) return ivoa::kExitFailure;
    }
    if (i < o.foreign) {
      const auto bytes = foreign_payload(i);
      for (const auto& channel : o.foreign_channels)
        if (!bus.publish_raw(channel, bytes.data(), bytes.size())) return ivoa::kExitFailure;
    }
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  return ivoa::kExitOk;
}

struct WaitOptions {
  std::string process = "logger";
  int pid = 0;  // 0: any process of that name
  int64_t min_in = -1;
  std::string counter;
  int64_t min_counter = 0;
  double timeout_s = 20;
};

bool condition_met(const ivoa::process_status_t& s, const WaitOptions& o) {
  if (o.min_in >= 0 && s.messages_in < o.min_in) return false;
  if (o.counter.empty()) return true;
  for (size_t i = 0; i < s.counter_names.size(); ++i)
    if (s.counter_names[i] == o.counter) return s.counter_values[i] >= o.min_counter;
  return false;
}

int wait(ivoa::Bus& bus, const WaitOptions& o) {
  bool met = false;
  ivoa::process_status_t last;
  bus.subscribe<ivoa::process_status_t>(ivoa::channels::kProcessStatus,
                                        [&](const ivoa::process_status_t& s, const ivoa::ReceiveInfo&) {
                                          if (s.name != o.process || (o.pid != 0 && s.pid != o.pid)) return;
                                          last = s;
                                          met = met || condition_met(s, o);
                                        });
  const double deadline = ivoa::monotonic_ms() + o.timeout_s * 1000.0;
  while (!met && ivoa::monotonic_ms() < deadline) bus.handle(50);
  spdlog::info("{}: last status: in {}, out {}, dropped {}, state '{}'", met ? "condition met" : "TIMED OUT",
               last.messages_in, last.messages_out, last.dropped, last.state);
  return met ? ivoa::kExitOk : ivoa::kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Helper processes for the logger tests"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  app.require_subcommand(1);
  PublishOptions p;
  auto* pub = app.add_subcommand("publish", "publish rig calibrations and messages of no ivoa type");
  pub->add_option("--calibrations", p.calibrations)->capture_default_str();
  pub->add_option("--foreign", p.foreign, "messages per foreign channel")->capture_default_str();
  pub->add_option("--foreign-channel", p.foreign_channels)->capture_default_str();
  pub->add_option("--rate", p.rate_hz)->capture_default_str()->check(ivoa::positive_number());
  WaitOptions w;
  auto* wt = app.add_subcommand("wait", "wait until a process's heartbeat shows a condition");
  wt->add_option("--process", w.process)->capture_default_str();
  wt->add_option("--pid", w.pid, "only the process with this pid");
  wt->add_option("--min-in", w.min_in, "messages_in at least this");
  wt->add_option("--counter", w.counter, "a named counter ...");
  wt->add_option("--min-counter", w.min_counter, "... at least this")->capture_default_str();
  wt->add_option("--timeout", w.timeout_s)->capture_default_str();
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("logger-test-helper", common.log_level);
  ivoa::Bus bus(common.lcm_url);
  return pub->parsed() ? publish(bus, p) : wait(bus, w);
}
