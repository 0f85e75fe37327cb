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

std::string LastHeartbeats::table() const {
  if (processes_.empty()) return "";
  std::string out = fmt::format("{:<24} {:>8} {:>4} {:<26} {:>8} {:>8} {:>6} {:>6}\n", "PROCESS (last heartbeat)",
                                "PID", "RUNS", "STATE", "IN", "OUT", "DROP", "BAD");
  for (const auto& [name, p] : processes_) {
    const process_status_t& s = p.status;
    out += fmt::format("{:<24} {:>8} {:>4} {:<26} {:>8} {:>8} {:>6} {:>6}\n", name, s.pid, p.pids.size(), s.state,
                       s.messages_in, s.messages_out, s.dropped, s.bad_input);
  }
  return out;
}

std::string LastHeartbeats::json() const {
  std::string out = "{";
  const char* sep = "\n  ";
  for (const auto& [name, p] : processes_) {
    const process_status_t& s = p.status;
    out += fmt::format(
        "{}{}: {{\"state\": {}, \"pid\": {}, \"runs\": {}, \"heartbeats\": {}, \"utime\": {}, \"messages_in\": {}, "
        "\"messages_out\": {}, \"dropped\": {}, \"bad_input\": {}, \"last_error\": {}}}",
        sep, json_quote(name), json_quote(s.state), s.pid, p.pids.size(), p.heartbeats, s.utime, s.messages_in,
        s.messages_out, s.dropped, s.bad_input, json_quote(s.last_error));
    sep = ",\n  ";
  }
  return out + "}";
}

}  // namespace ivoa::log_check
