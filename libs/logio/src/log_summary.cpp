#include "ivoa/logio/log_summary.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "ivoa/core/json_text.hpp"
#include "ivoa/core/message_registry.hpp"
#include "ivoa/logio/log_reader.hpp"

namespace ivoa::logio {
namespace {

// `time_went_on`: the message's utime is later than the one before it. A
// seq that goes back while time goes on is its publisher starting again
// (respawned); the new run's numbers before it were lost. Otherwise it is
// a repeat or a late message, and the run's newest seq stays.
void add_seq(ChannelSummary& s, int64_t seq, bool time_went_on) {
  if (s.typed == 1) {
    s.first_seq = seq;
  } else if (seq <= s.last_seq && time_went_on) {
    ++s.seq_restarts;
    s.missing_seq += seq;
  } else if (seq <= s.last_seq) {
    ++s.seq_regressions;
    return;
  } else if (seq > s.last_seq + 1) {
    s.missing_seq += seq - s.last_seq - 1;
    if (s.gaps.size() < kMaxGapsListed) s.gaps.push_back({s.last_seq, seq});
  }
  s.last_seq = seq;
}

}  // namespace

void LogSummary::add(const LogEvent& event) {
  add(event.channel, event.timestamp, event.data.data(), event.data.size());
}

void LogSummary::add(const std::string& channel, int64_t timestamp, const void* data, size_t size) {
  ++events_;
  bytes_ += size;
  ChannelSummary& s = channels_[channel];
  const int64_t fingerprint = payload_fingerprint(data, size).value_or(0);
  const auto type = payload_type_name(data, size);
  if (s.count == 0) s.first_timestamp = timestamp;
  ++s.count;
  s.bytes += size;
  s.last_timestamp = timestamp;
  // The channel's type is its first message's, or the first ivoa type on it
  // if that one was of none (damaged at its start, or foreign).
  if (s.count == 1 || (s.type == "unknown" && type)) {
    const int64_t count = s.count;
    const uint64_t bytes = s.bytes;
    const int64_t first_timestamp = s.first_timestamp;
    s = ChannelSummary{};  // what was counted of the first type was not of this one
    s.count = count, s.bytes = bytes, s.first_timestamp = first_timestamp, s.last_timestamp = timestamp;
    s.other_fingerprints = s.count - 1;
    if (s.other_fingerprints > 0) s.other_types[kNoIvoaType] = s.other_fingerprints;
    s.fingerprint = fingerprint;
    s.type = std::string(type.value_or("unknown"));
    s.has_seq = type_has_seq(s.type);
    s.utime_ordered = !type_has_many_senders(s.type);
  }
  // A channel of another program's types: its messages are all "unknown"
  // alike, not one type among others ("4 of its 5 are not unknown").
  const bool foreign_alike = s.type == "unknown" && !type;
  if (fingerprint != s.fingerprint && !foreign_alike) {
    ++s.other_fingerprints;
    ++s.other_types[type ? std::string(*type) : kNoIvoaType];
    return;
  }
  ++s.typed;
  const auto utime = payload_utime(data, size);
  if (s.type == "unknown" || !utime) return;
  const bool time_went_on = s.typed > 1 && *utime > s.last_utime;
  if (s.typed == 1) s.first_utime = *utime;
  else if (*utime < s.last_utime && s.utime_ordered) ++s.utime_regressions;
  s.last_utime = *utime;
  if (const auto seq = payload_seq(s.type, data, size)) add_seq(s, *seq, time_went_on);
}

std::string LogSummary::table() const {
  // fmt, not a fixed buffer: channel names run to 255 bytes
  std::string out = fmt::format("{:<24} {:<28} {:>8} {:>10} {:>9} {:>9} {:>8} {:>8}\n", "channel", "type", "count",
                                "MB", "first seq", "last seq", "missing", "utime<");
  for (const auto& [name, s] : channels_) {
    const auto seq = [&s](int64_t v) { return s.has_seq ? std::to_string(v) : std::string("-"); };
    const std::string regressions = s.utime_ordered ? std::to_string(s.utime_regressions) : "-";
    out += fmt::format("{:<24} {:<28} {:>8} {:>10.1f} {:>9} {:>9} {:>8} {:>8}\n", name, s.type, s.count,
                       static_cast<double>(s.bytes) / 1e6, seq(s.first_seq), seq(s.last_seq), seq(s.missing_seq),
                       regressions);
  }
  for (const auto& [name, s] : channels_) {  // the table's seq columns span every run of the publisher
    if (s.seq_restarts > 0)
      out += fmt::format(
          "{}: its sequence started again {} time{} (went back as time went on: a publisher restarted); "
          "\"missing\" counts within each run\n",
          name, s.seq_restarts, s.seq_restarts == 1 ? "" : "s");
    if (s.seq_regressions > 0)
      out += fmt::format("{}: {} message{} repeated or out of order by sequence number\n", name, s.seq_regressions,
                         s.seq_regressions == 1 ? "" : "s");
  }
  for (const auto& [name, s] : channels_) {  // one type per channel: a reader of the first skips these
    if (s.other_fingerprints == 0) continue;
    std::string which;
    for (const auto& [type, n] : s.other_types) which += fmt::format("{}{} {}", which.empty() ? "" : ", ", n, type);
    if (s.other_types.count(kNoIvoaType)) which += ": another program's, or damaged before the fingerprint";
    out +=
        fmt::format("{}: {} of its {} messages are not {} ({})\n", name, s.other_fingerprints, s.count, s.type, which);
  }
  return out;
}

std::string fingerprint_hex(int64_t fingerprint) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "\"0x%016llx\"", static_cast<unsigned long long>(fingerprint));
  return buf;
}

std::string channel_json(const ChannelSummary& s) {
  std::string out = "{\"type\": " + json_quote(s.type) + ", \"fingerprint\": " + fingerprint_hex(s.fingerprint) +
                    ", \"count\": " + std::to_string(s.count) + ", \"bytes\": " + std::to_string(s.bytes) +
                    ", \"first_timestamp\": " + std::to_string(s.first_timestamp) +
                    ", \"last_timestamp\": " + std::to_string(s.last_timestamp);
  if (s.type != "unknown")
    out += ", \"first_utime\": " + std::to_string(s.first_utime) + ", \"last_utime\": " + std::to_string(s.last_utime);
  if (s.type != "unknown" && s.utime_ordered) out += ", \"utime_regressions\": " + std::to_string(s.utime_regressions);
  if (s.has_seq) {
    out += ", \"first_seq\": " + std::to_string(s.first_seq) + ", \"last_seq\": " + std::to_string(s.last_seq) +
           ", \"missing_seq\": " + std::to_string(s.missing_seq) +
           ", \"seq_regressions\": " + std::to_string(s.seq_regressions) +
           ", \"seq_restarts\": " + std::to_string(s.seq_restarts) + ", \"gaps\": [";
    for (size_t i = 0; i < s.gaps.size(); ++i)
      out += (i ? ", [" : "[") + std::to_string(s.gaps[i].after) + ", " + std::to_string(s.gaps[i].next) + "]";
    out += "]";
  }
  if (s.other_fingerprints > 0) out += ", \"other_types\": " + std::to_string(s.other_fingerprints);
  return out + "}";
}

}  // namespace ivoa::logio
