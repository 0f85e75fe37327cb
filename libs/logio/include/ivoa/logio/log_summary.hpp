#pragma once
// What a log holds, per channel: message type (by fingerprint), count,
// bytes, time span, and for types with a sequence number the gaps in it.
// Every ivoa type starts with int64 utime; stereo_image_t and
// depth_image_t have int64 seq next, so both are read without decoding.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace ivoa::logio {
struct LogEvent;

struct SeqGap {
  int64_t after = 0;  // the last sequence number seen before the gap
  int64_t next = 0;   // the one that came next
};

struct ChannelSummary {
  std::string type = "unknown";  // "ivoa.stereo_image_t", or unknown: its first message's, or its first ivoa type
  int64_t fingerprint = 0;       // of that type
  int64_t count = 0;
  uint64_t bytes = 0;
  int64_t other_fingerprints = 0;              // messages of another type than the channel's (one type per channel!)
  std::map<std::string, int64_t> other_types;  // those by type name; kNoIvoaType for the rest
  int64_t typed = 0;                           // messages of the channel's type
  int64_t first_timestamp = 0, last_timestamp = 0;  // log (receive) time
  int64_t first_utime = 0, last_utime = 0;          // message utime, ivoa types only
  int64_t utime_regressions = 0;                    // message utime went backwards
  bool utime_ordered = true;                        // false for heartbeats, whose senders interleave: not counted
  bool has_seq = false;
  int64_t first_seq = -1, last_seq = -1;
  int64_t missing_seq = 0;      // messages missing according to seq
  int64_t seq_regressions = 0;  // seq repeated or went back at the same or an older utime
  int64_t seq_restarts = 0;     // seq went back as utime went on: its publisher started again (respawned)
  std::vector<SeqGap> gaps;     // the first kMaxGapsListed of them
};

inline constexpr size_t kMaxGapsListed = 20;
// other_types' key of payloads whose fingerprint is no ivoa type's.
inline constexpr const char* kNoIvoaType = "no ivoa type";

// JSON for tools and sidecars (strings: ivoa::json_quote): a channel as
// one object; a fingerprint as a "0x..." string (JSON readers lose
// precision on 64-bit integers).
std::string channel_json(const ChannelSummary& summary);
std::string fingerprint_hex(int64_t fingerprint);

class LogSummary {
 public:
  void add(const LogEvent& event);
  void add(const std::string& channel, int64_t timestamp, const void* data, size_t size);

  const std::map<std::string, ChannelSummary>& channels() const { return channels_; }
  int64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }
  // A fixed-width table, one line per channel, for people.
  std::string table() const;

 private:
  std::map<std::string, ChannelSummary> channels_;
  int64_t events_ = 0;
  uint64_t bytes_ = 0;
};

}  // namespace ivoa::logio
