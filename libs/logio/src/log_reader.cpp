#include "ivoa/logio/log_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>

#include "ivoa/logio/log_format.hpp"

namespace ivoa::logio {
namespace {

bool printable(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c < 0x7F; });
}

std::string hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%08X", v);
  return buf;
}

}  // namespace

std::string LogProblem::describe() const {
  std::string s = "byte " + std::to_string(offset) + ": " + what;
  if (skipped_bytes > 0)
    s += " (" + std::to_string(skipped_bytes) +
         (to_end ? " bytes to the end of the file not read)" : " bytes skipped to the next good event)");
  return s;
}

std::string LogReader::not_a_log() const {
  if (problems_.empty() || problems_.front().offset != 0 || !problems_.front().to_end) return "";
  return "not an LCM log, or damaged from its start (" + problems_.front().describe() + ")";
}

LogReader::LogReader(std::string path, LogReaderOptions options) : path_(std::move(path)), options_(options) {
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd_ < 0 || ::fstat(fd_, &st) != 0) {
    const int error = errno;
    if (fd_ >= 0) ::close(fd_);
    throw LogReadError("cannot open log " + path_ + ": " + std::strerror(error));
  }
  // Events are read at their offsets: a pipe or device read as a file of
  // size 0 passed as an intact, empty log.
  if (!S_ISREG(st.st_mode)) {
    ::close(fd_);
    throw LogReadError("cannot read log " + path_ +
                       ": not a regular file (a pipe or a device: save it to a file first)");
  }
  size_ = static_cast<uint64_t>(st.st_size);
  ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

LogReader::~LogReader() { ::close(fd_); }

void LogReader::read_exactly(void* out, size_t bytes, uint64_t offset) {
  auto* p = static_cast<uint8_t*>(out);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd_, p, bytes, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw LogReadError("cannot read log " + path_ + " at byte " + std::to_string(offset) + ": " +
                         (n < 0 ? std::strerror(errno) : "the file shrank while being read"));
    p += n;
    bytes -= static_cast<size_t>(n);
    offset += static_cast<uint64_t>(n);
  }
}

std::string LogReader::check_event_at(uint64_t offset, EventHeader& h, std::string& channel, bool& cut_short) {
  cut_short = false;
  const uint64_t left = size_ - offset;
  if (left < kEventHeaderBytes) {
    uint8_t start[4] = {};
    const size_t present = static_cast<size_t>(std::min<uint64_t>(left, sizeof(start)));
    read_exactly(start, present, offset);
    cut_short = std::equal(start, start + present, kSyncBytes);  // not garbage after the last event
    return "truncated: the file ends " + std::to_string(left) + " bytes into an event header";
  }
  uint8_t head[kEventHeaderBytes];
  read_exactly(head, sizeof(head), offset);
  h = decode_header(head);
  if (h.sync != kSyncWord)
    return "no event starts here (sync word " + hex32(h.sync) + ", expected " + hex32(kSyncWord) + ")";
  if (h.channel_bytes == 0 || h.channel_bytes > kMaxChannelBytes)
    return "corrupt event header: channel name length " + std::to_string(h.channel_bytes);
  if (h.data_bytes > kMaxDataBytes) return "corrupt event header: message length " + std::to_string(h.data_bytes);
  if (h.event_bytes() > left) {
    cut_short = true;
    return "truncated: event " + std::to_string(h.event_number) + " needs " + std::to_string(h.event_bytes()) +
           " bytes but the file ends after " + std::to_string(left);
  }
  channel.resize(h.channel_bytes);
  read_exactly(channel.data(), channel.size(), offset + kEventHeaderBytes);
  if (!printable(channel)) return "corrupt event: the channel name is not printable text";
  return {};
}

bool LogReader::next(LogEvent& event) {
  while (!stopped_ && position_ < size_) {
    const uint64_t offset = position_;
    EventHeader h;
    bool cut_short = false;
    if (std::string what = check_event_at(offset, h, event.channel, cut_short); !what.empty()) {
      if (!recover(offset, std::move(what), cut_short)) return false;
      continue;
    }
    event.offset = offset;
    event.event_number = h.event_number;
    event.timestamp = h.timestamp;
    event.data.resize(options_.headers_only ? 0 : h.data_bytes);
    if (!options_.headers_only)
      read_exactly(event.data.data(), h.data_bytes, offset + kEventHeaderBytes + h.channel_bytes);
    position_ = offset + h.event_bytes();
    return true;
  }
  return false;
}

// Records the problem; with resync, moves to the next plausible event.
bool LogReader::recover(uint64_t offset, std::string what, bool cut_short) {
  const uint64_t next_event = options_.resync ? find_next_event(offset + 1) : size_;
  stopped_ = next_event >= size_;
  problems_.push_back({offset, std::move(what), next_event - offset, stopped_, cut_short});
  position_ = next_event;
  return !stopped_;
}

// The offset of the next sync word that starts a plausible event, or the
// file size if there is none.
uint64_t LogReader::find_next_event(uint64_t from) {
  std::vector<uint8_t> chunk(1 << 20);
  EventHeader header;
  std::string channel;
  bool cut_short = false;
  for (uint64_t base = from; base + sizeof(kSyncBytes) <= size_;) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(chunk.size(), size_ - base));
    read_exactly(chunk.data(), n, base);
    for (auto it = chunk.begin(); (it = std::search(it, chunk.begin() + static_cast<long>(n), std::begin(kSyncBytes),
                                                    std::end(kSyncBytes))) != chunk.begin() + static_cast<long>(n);
         ++it) {
      const uint64_t candidate = base + static_cast<uint64_t>(it - chunk.begin());
      if (check_event_at(candidate, header, channel, cut_short).empty()) return candidate;
    }
    if (n < sizeof(kSyncBytes)) break;
    base += n - (sizeof(kSyncBytes) - 1);  // overlap so a sync word across chunks is found
  }
  return size_;
}

}  // namespace ivoa::logio
