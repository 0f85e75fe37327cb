#include "ivoa/logger/disk_reserve.hpp"

#include <utility>

#include <spdlog/spdlog.h>

#include "ivoa/core/disk_space.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/logio/log_writer.hpp"

namespace ivoa::logger {
namespace {

std::string mb_text(uint64_t bytes) { return std::to_string(bytes / 1'000'000) + " MB"; }

constexpr const char* kWhatToDo = "free some space: a respawned logger records again once there is room";

}  // namespace

DiskReserve::DiskReserve(std::string log_path, DiskReserveOptions options)
    : log_path_(std::move(log_path)), options_(std::move(options)) {
  if (options_.min_free_bytes == 0) return;
  if (!options_.free_bytes) options_.free_bytes = [path = log_path_] { return free_bytes_for(path); };
  look(monotonic_ms(), 0);
  const uint64_t to_start = options_.min_free_bytes + options_.min_free_bytes / 4;
  if (last_free_ && *last_free_ < to_start)
    throw logio::LogWriteError("only " + mb_text(*last_free_) + " free on the disk of " + log_path_ + ", under the " +
                               mb_text(to_start) + " a start needs (--min-free-mb " +
                               std::to_string(options_.min_free_bytes / 1'000'000) +
                               " and a quarter more): not recording (" + kWhatToDo + ")");
}

void DiskReserve::check(double now_ms, uint64_t bytes_written, uint64_t next_bytes) {
  if (options_.min_free_bytes == 0) return;
  const auto short_of_room = [&] {
    return last_free_ && *last_free_ < bytes_written - bytes_at_last_look_ + next_bytes + options_.min_free_bytes;
  };
  if (now_ms - last_look_ms_ >= options_.period_s * 1000.0 ||
      bytes_written - bytes_at_last_look_ >= options_.min_free_bytes / 4 || short_of_room())
    look(now_ms, bytes_written);
  if (short_of_room())
    throw logio::LogWriteError("only " + mb_text(*last_free_) + " free on the disk of " + log_path_ + ": the next " +
                               std::to_string(next_bytes) + "-byte event would leave less than --min-free-mb " +
                               std::to_string(options_.min_free_bytes / 1'000'000) +
                               ", so recording stopped to leave that for the system (" + kWhatToDo + ")");
}

void DiskReserve::look(double now_ms, uint64_t bytes_written) {
  last_look_ms_ = now_ms;
  bytes_at_last_look_ = bytes_written;
  last_free_ = options_.free_bytes();
  if (!last_free_ && !unreadable_warned_) {
    spdlog::warn("cannot read the free space of the disk of {}: --min-free-mb does not hold", log_path_);
    unreadable_warned_ = true;
  }
}

}  // namespace ivoa::logger
