#pragma once
// The logger's running totals, shared by the receive thread, the writer
// thread and the heartbeat. received = written + dropped + (after a write
// error) the messages that never reached the disk.
#include <atomic>
#include <cstdint>

namespace ivoa::logger {

struct SessionCounters {
  std::atomic<int64_t> received{0};  // messages accepted by the channel filter
  std::atomic<int64_t> written{0};   // events written to the log (calibration copies excluded)
  std::atomic<int64_t> dropped{0};   // refused because the queue was full (disk too slow)
  std::atomic<int64_t> dropped_bytes{0};
  std::atomic<int64_t> bytes_written{0};  // payload and channel bytes, calibration copies included
  std::atomic<int64_t> files{0};          // log files opened
  std::atomic<int64_t> deleted{0};        // of the written, in a file deleted while recording: gone with it
};

}  // namespace ivoa::logger
