#include "ivoa/logger/disk_reserve.hpp"

#include <utility>

#include "ivoa/core/disk_space.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/logio/log_writer.hpp"

namespace ivoa::logger {
namespace {

std::string mb_text(uint64_t bytes) { return std::to_string(bytes / 1'000'000) + " MB"; }

}  // namespace

DiskReserve::DiskReserve(std::string log_path, DiskReserveOptions options)
    : log_path_(std::move(log_path)), options_(std::move(options)) {
  if (!options_.free_bytes) options_.free_bytes = [path = log_path_] { return free_bytes_for(path); };
  look();
  last_look_ms_ = monotonic_ms();
}

void DiskReserve::check(double now_ms, uint64_t bytes_written) {
  if (now_ms - last_look_ms_ < options_.period_s * 1000.0 &&
      bytes_written - bytes_at_last_look_ < options_.min_free_bytes / 4)
    return;
  last_look_ms_ = now_ms;
  bytes_at_last_look_ = bytes_written;
  look();
}

void DiskReserve::look() {
  if (options_.min_free_bytes == 0) return;
  const std::optional<uint64_t> free = options_.free_bytes();
  if (!free || *free >= options_.min_free_bytes) return;  // a file system that cannot say: nothing to go by
  throw logio::LogWriteError("only " + mb_text(*free) + " free on the disk of " + log_path_ + ", under --min-free-mb " +
                             std::to_string(options_.min_free_bytes / 1'000'000) +
                             ": not recording, to leave that for the system (free some space: a respawned logger "
                             "records again once there is room)");
}

}  // namespace ivoa::logger
