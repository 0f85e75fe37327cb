#include "ivoa/logger/sidecar.hpp"

#include <algorithm>
#include <sstream>

#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/message_registry.hpp"
#include "ivoa/logio/log_summary.hpp"

namespace ivoa::logger {
namespace {

using ivoa::json_quote;
using logio::fingerprint_hex;

std::string base_name(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void write_channels(std::ostringstream& out, const logio::LogSummary& summary) {
  out << "  \"channels\": {";
  const char* sep = "\n";
  for (const auto& [name, channel] : summary.channels()) {
    out << sep << "    " << json_quote(name) << ": " << logio::channel_json(channel);
    sep = ",\n";
  }
  out << "\n  },\n";
}

void write_session(std::ostringstream& out, const SessionCounters& n) {
  out << "  \"session\": {\"received\": " << n.received << ", \"written\": " << n.written
      << ", \"dropped\": " << n.dropped << ", \"dropped_bytes\": " << n.dropped_bytes
      << ", \"bytes_written\": " << n.bytes_written << ", \"files\": " << n.files << ", \"deleted\": " << n.deleted
      << "},\n";
}

void write_message_types(std::ostringstream& out) {
  out << "  \"message_types\": {";
  const char* sep = "\n";
  for (const auto& t : message_types()) {
    out << sep << "    " << json_quote(std::string(t.name)) << ": " << fingerprint_hex(t.fingerprint);
    sep = ",\n";
  }
  out << "\n  }\n";
}

}  // namespace

std::string sidecar_path(const std::string& log_path) { return log_path + ".json"; }

std::string sidecar_json(const SidecarContent& c) {
  const LoggerIdentity& id = *c.identity;
  const logio::LogSummary& s = *c.summary;
  int64_t start = 0, end = 0;
  for (const auto& [name, ch] : s.channels()) {
    if (start == 0 || ch.first_timestamp < start) start = ch.first_timestamp;
    end = std::max(end, ch.last_timestamp);
  }
  const auto flag = [](bool b) { return b ? "true" : "false"; };
  std::ostringstream out;
  out << "{\n  \"log\": " << json_quote(base_name(c.log_path)) << ",\n  \"part\": " << c.part
      << ",\n  \"complete\": " << flag(c.complete) << ",\n  \"error\": " << json_quote(c.error) << ",\n";
  out << "  \"logger\": {\"program\": " << json_quote(id.program) << ", \"version\": " << json_quote(id.version)
      << ", \"git\": " << json_quote(id.git) << ", \"host\": " << json_quote(id.host) << "},\n";
  out << "  \"lcm_url\": " << json_quote(id.lcm_url) << ",\n  \"channels_regex\": " << json_quote(id.channels_regex)
      << ",\n  \"exclude_regex\": " << json_quote(id.exclude_regex) << ",\n";
  out << "  \"start_utime\": " << start << ",\n  \"end_utime\": " << end << ",\n  \"events\": " << s.events()
      << ",\n  \"payload_bytes\": " << s.bytes() << ",\n  \"file_bytes\": " << c.file_bytes
      << ",\n  \"starts_with_calibration\": " << flag(c.starts_with_calibration) << ",\n";
  write_channels(out, s);
  write_session(out, *c.counters);
  write_message_types(out);
  out << "}\n";
  return out.str();
}

// Replaced whole, so a logger killed mid-write leaves the previous sidecar
// rather than half of the new one.
bool write_sidecar(const SidecarContent& content, std::string& error) {
  return replace_file(sidecar_path(content.log_path), sidecar_json(content), error);
}

}  // namespace ivoa::logger
