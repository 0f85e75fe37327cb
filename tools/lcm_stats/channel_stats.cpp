#include "channel_stats.hpp"

#include <cstdio>
#include <sstream>

#include "ivoa/core/message_registry.hpp"

namespace ivoa::tools {

double ChannelStats::rate_hz() const {
  const double span_s = static_cast<double>(last_recv_utime - first_recv_utime) * 1e-6;
  return count > 1 && span_s > 0 ? static_cast<double>(count - 1) / span_s : 0.0;
}

void TrafficStats::add(const std::string& channel, const void* data, size_t size, int64_t recv_utime) {
  ChannelStats& s = channels_[channel];
  if (s.count == 0) {
    s.first_recv_utime = recv_utime;
    s.type = std::string(payload_type_name(data, size).value_or("unknown"));
  }
  ++s.count;
  s.bytes += static_cast<int64_t>(size);
  s.last_recv_utime = recv_utime;
  const auto utime = payload_utime(data, size);
  if (s.type == "unknown" || !utime) return;
  if (s.count > 1 && *utime < s.last_utime) ++s.utime_regressions;
  s.last_utime = *utime;
  if (const auto seq = payload_seq(s.type, data, size)) s.seq_gaps += s.seq_counter.add(*seq);
}

std::string TrafficStats::table() const {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof(line), "%-24s %-30s %8s %8s %10s %8s\n", "channel", "type", "count", "Hz", "MB/s",
                "seq gaps");
  out << line;
  for (const auto& [name, s] : channels_) {
    const double span_s = static_cast<double>(s.last_recv_utime - s.first_recv_utime) * 1e-6;
    const double mbps = span_s > 0 ? static_cast<double>(s.bytes) / span_s / 1e6 : 0.0;
    std::snprintf(line, sizeof(line), "%-24s %-30s %8lld %8.1f %10.2f %8lld\n", name.c_str(), s.type.c_str(),
                  static_cast<long long>(s.count), s.rate_hz(), mbps, static_cast<long long>(s.seq_gaps));
    out << line;
  }
  return out.str();
}

std::string TrafficStats::json() const {
  std::ostringstream out;
  out << "{\"channels\": {";
  bool first = true;
  for (const auto& [name, s] : channels_) {
    out << (first ? "" : ", ") << "\"" << name << "\": {\"type\": \"" << s.type << "\", \"count\": " << s.count
        << ", \"bytes\": " << s.bytes << ", \"hz\": " << s.rate_hz() << ", \"seq_gaps\": " << s.seq_gaps
        << ", \"utime_regressions\": " << s.utime_regressions << "}";
    first = false;
  }
  out << "}}\n";
  return out.str();
}

}  // namespace ivoa::tools
