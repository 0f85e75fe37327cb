#pragma once
#include <chrono>
#include <cstdint>

namespace ivoa {

// Microseconds since the Unix epoch: the unit of every message's utime.
inline int64_t now_utime() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

// Monotonic milliseconds, for latency and rate measurements.
inline double monotonic_ms() {
  using namespace std::chrono;
  return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

}  // namespace ivoa
