#pragma once
// Per-channel traffic statistics from raw LCM payloads: count, bytes, rate,
// the ivoa type (by fingerprint) and, for types with a sequence number,
// gaps in it. Every ivoa type starts with utime, so it is read generically.
#include <cstdint>
#include <map>
#include <string>

#include "ivoa/core/seq_gaps.hpp"

namespace ivoa::tools {

struct ChannelStats {
  std::string type = "unknown";
  int64_t count = 0;
  int64_t bytes = 0;
  int64_t first_recv_utime = 0;
  int64_t last_recv_utime = 0;
  int64_t last_utime = 0;         // message utime
  int64_t utime_regressions = 0;  // message utime went backwards
  SeqGaps seq_counter;
  int64_t seq_gaps = 0;  // messages missing according to seq

  double rate_hz() const;
};

class TrafficStats {
 public:
  void add(const std::string& channel, const void* data, size_t size, int64_t recv_utime);
  const std::map<std::string, ChannelStats>& channels() const { return channels_; }
  std::string table() const;
  std::string json() const;

 private:
  std::map<std::string, ChannelStats> channels_;
};

}  // namespace ivoa::tools
