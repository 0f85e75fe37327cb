#include "ivoa/log_check/last_heartbeats.hpp"

#include <fmt/format.h>

#include "ivoa/core/json_text.hpp"

namespace ivoa::log_check {

void LastHeartbeats::add(const logio::LogEvent& event) {
  process_status_t status;
  if (!logio::decode(event, status)) return;
  LastHeartbeat& last = processes_[status.name];
  last.pids.insert(status.pid);
  ++last.heartbeats;
  if (last.heartbeats == 1 || status.utime >= last.status.utime) last.status = std::move(status);
}

namespace {

// A heartbeat's text as the terminal may show it: control bytes (an escape
// sequence in a process name cleared the screen) become '?'.
std::string shown(const std::string& text) {
  std::string out = text;
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return out;
}

// A process's own counters that are not 0 ("frames_missed 7, ..."): what
// IN/OUT/DROP/BAD do not say, such as frames that never arrived.
std::string nonzero_counters(const process_status_t& s) {
  std::string out;
  for (size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i)
    if (s.counter_values[i] != 0)
      out += fmt::format("{}{} {}", out.empty() ? "" : ", ", shown(s.counter_names[i]), s.counter_values[i]);
  return out;
}

std::string counters_json(const process_status_t& s) {
  std::string out;
  for (size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i)
    out += fmt::format("{}{}: {}", i ? ", " : "", json_quote(s.counter_names[i]), s.counter_values[i]);
  return out;
}

}  // namespace

std::string LastHeartbeats::table() const {
  if (processes_.empty()) return "";
  std::string out = fmt::format("{:<24} {:>8} {:>4} {:<26} {:>8} {:>8} {:>6} {:>6}  {}\n", "PROCESS (last heartbeat)",
                                "PID", "RUNS", "STATE", "IN", "OUT", "DROP", "BAD", "COUNTERS (not 0)");
  for (const auto& [name, p] : processes_) {
    const process_status_t& s = p.status;
    out += fmt::format("{:<24} {:>8} {:>4} {:<26} {:>8} {:>8} {:>6} {:>6}  {}\n", shown(name), s.pid, p.pids.size(),
                       shown(s.state), s.messages_in, s.messages_out, s.dropped, s.bad_input, nonzero_counters(s));
  }
  // The logger closes the log before it (and the launcher above it) stops,
  // so their final heartbeats can never be in it: not a fault.
  if (processes_.count("logger") > 0 || processes_.count("launcher") > 0)
    out += "(logger, launcher: the log closes before they stop, so their last heartbeat in it is a running one)\n";
  return out;
}

std::string LastHeartbeats::json() const {
  std::string out = "{";
  const char* sep = "\n  ";
  for (const auto& [name, p] : processes_) {
    const process_status_t& s = p.status;
    out += fmt::format(
        "{}{}: {{\"state\": {}, \"pid\": {}, \"runs\": {}, \"heartbeats\": {}, \"utime\": {}, \"messages_in\": {}, "
        "\"messages_out\": {}, \"dropped\": {}, \"bad_input\": {}, \"last_error\": {}, \"counters\": {{{}}}}}",
        sep, json_quote(name), json_quote(s.state), s.pid, p.pids.size(), p.heartbeats, s.utime, s.messages_in,
        s.messages_out, s.dropped, s.bad_input, json_quote(s.last_error), counters_json(s));
    sep = ",\n  ";
  }
  return out + "}";
}

}  // namespace ivoa::log_check
