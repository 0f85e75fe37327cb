#pragma once
#include <chrono>
#include <cstdint>
#include <string>

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

// A file name pattern with strftime's fields (%Y, %m, %d, %H, %M, %S...)
// filled in with the local time now; "" if it expands to nothing (or past
// 4 KiB). Gives each run of a respawned recorder its own file.
std::string expand_time_pattern(const std::string& pattern);

}  // namespace ivoa
