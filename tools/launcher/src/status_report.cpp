#include "ivoa/launcher/status_report.hpp"

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "ivoa/core/json_text.hpp"

namespace ivoa::launcher {
namespace {

std::string fixed(double v, int decimals) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

std::string state_text(const CommandStatus& c) {
  std::string s = to_string(c.state);
  if (c.state == RunState::kRespawning) s += " " + fixed(c.respawn_in_s, 1) + "s";
  return s;
}

// The process-specific counters, {"name": value, ...}.
std::string counters_json(const process_status_t& h) {
  std::string out = "{";
  const size_t n = std::min(h.counter_names.size(), h.counter_values.size());
  for (size_t i = 0; i < n; ++i)
    out += (i ? ", " : "") + json_quote(h.counter_names[i]) + ": " + std::to_string(h.counter_values[i]);
  return out + "}";
}

// The counts of the command's earlier instances (0 of them: never respawned).
std::string earlier_json(const InstanceCounts& e) {
  return "{\"instances\": " + std::to_string(e.instances) + ", \"messages_in\": " + std::to_string(e.messages_in) +
         ", \"messages_out\": " + std::to_string(e.messages_out) + ", \"dropped\": " + std::to_string(e.dropped) +
         ", \"bad_input\": " + std::to_string(e.bad_input) + "}";
}

std::string clip(const std::string& s, size_t width) { return s.size() <= width ? s : s.substr(0, width - 1) + "~"; }

}  // namespace

std::string describe_exit(const CommandStatus& c) {
  if (c.exit_signal != 0) {
    const char* abbrev = sigabbrev_np(c.exit_signal);
    return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(c.exit_signal);
  }
  return c.exit_code >= 0 ? std::to_string(c.exit_code) : "-";
}

std::string format_status_table(const std::vector<StatusRow>& rows) {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof(line), "%-20s %7s %-15s %4s %-8s %8s %8s %6s %5s %8s  %s\n", "NAME", "PID", "STATE", "RST",
                "EXIT", "IN", "OUT", "DROP", "BAD", "LAT ms", "PROCESS STATE");
  out << line;
  for (const auto& r : rows) {
    const auto& c = r.command;
    const std::string pid = c.pid > 0 ? std::to_string(c.pid) : "-";
    std::string in = "-", out_count = "-", dropped = "-", bad = "-", latency = "-", hb_state = "";
    if (r.heartbeat) {
      const auto& h = *r.heartbeat;
      in = std::to_string(h.messages_in + r.earlier.messages_in);
      out_count = std::to_string(h.messages_out + r.earlier.messages_out);
      dropped = std::to_string(h.dropped + r.earlier.dropped);
      bad = std::to_string(h.bad_input + r.earlier.bad_input);
      latency = fixed(h.latency_ms_mean, 1);
      hb_state = (r.heartbeat_sender_ended ? "ended; last said " : "") + h.state + " (" + fixed(r.heartbeat_age_s, 0) +
                 "s ago)";
    }
    std::snprintf(line, sizeof(line), "%-20s %7s %-15s %4d %-8s %8s %8s %6s %5s %8s  %s\n", clip(c.name, 20).c_str(),
                  pid.c_str(), state_text(c).c_str(), c.restarts, describe_exit(c).c_str(), in.c_str(),
                  out_count.c_str(), dropped.c_str(), bad.c_str(), latency.c_str(), clip(hb_state, 40).c_str());
    out << line;
  }
  return out.str();
}

std::string format_status_json(const std::vector<StatusRow>& rows, const RunSummary& summary) {
  std::ostringstream out;
  out << "{\"config\": " << json_quote(summary.config_path) << ", \"host\": " << json_quote(summary.host)
      << ", \"elapsed_s\": " << fixed(summary.elapsed_s, 3) << ", \"end_reason\": " << json_quote(summary.end_reason)
      << ", \"exit_code\": " << summary.exit_code << ",\n \"commands\": [";
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& c = rows[i].command;
    out << (i ? ",\n  " : "\n  ") << "{\"name\": " << json_quote(c.name) << ", \"group\": " << json_quote(c.group)
        << ", \"host\": " << json_quote(c.host) << ", \"auto_respawn\": " << (c.auto_respawn ? "true" : "false")
        << ", \"pid\": " << c.pid << ", \"state\": " << json_quote(to_string(c.state))
        << ", \"restarts\": " << c.restarts << ", \"exit_code\": " << c.exit_code
        << ", \"exit_signal\": " << c.exit_signal << ", \"failed\": " << (c.failed ? "true" : "false")
        << ", \"killed\": " << (c.killed ? "true" : "false")
        << ", \"earlier_instances\": " << earlier_json(rows[i].earlier) << ", \"heartbeat\": ";
    if (!rows[i].heartbeat) {
      out << "null}";
      continue;
    }
    const auto& h = *rows[i].heartbeat;
    out << "{\"name\": " << json_quote(h.name) << ", \"pid\": " << h.pid << ", \"messages_in\": " << h.messages_in
        << ", \"messages_out\": " << h.messages_out << ", \"dropped\": " << h.dropped
        << ", \"bad_input\": " << h.bad_input << ", \"latency_ms_mean\": " << fixed(h.latency_ms_mean, 3)
        << ", \"latency_ms_max\": " << fixed(h.latency_ms_max, 3) << ", \"state\": " << json_quote(h.state)
        << ", \"last_error\": " << json_quote(h.last_error) << ", \"age_s\": " << fixed(rows[i].heartbeat_age_s, 3)
        << ", \"counters\": " << counters_json(h) << "}}";
  }
  out << "\n]}\n";
  return out.str();
}

}  // namespace ivoa::launcher
