#include "ivoa/logio/log_writer.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "ivoa/logio/log_format.hpp"

namespace ivoa::logio {

LogWriter::LogWriter(std::string path, LogWriterOptions options) : path_(std::move(path)), options_(options) {
  // Not O_TRUNC: an existing file is emptied only once this writer holds it.
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (options_.overwrite ? 0 : O_EXCL);
  fd_ = ::open(path_.c_str(), flags, 0644);
  if (fd_ < 0) {
    const int error = errno;
    std::error_code ignored;
    if (std::filesystem::is_directory(path_, ignored))  // EEXIST or EISDIR: --force would not help
      throw LogWriteError("cannot create log " + path_ + ": it is a folder (name a file in it)");
    throw LogWriteError(
        "cannot create log " + path_ + ": " + std::strerror(error) +
        (error == EEXIST ? " (--force overwrites it, --increment records to a new NAME-1, NAME-2, ...)" : ""));
  }
  hold_for_writing();
}

// An exclusive flock for the writer's life: a second writer of the same
// file (a logger started twice with --force) used to empty and overwrite
// what the first one was recording, and both reported success.
void LogWriter::hold_for_writing() {
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    if (error == EWOULDBLOCK) {
      ::close(fd_);
      fd_ = -1;
      throw LogWriteError("cannot create log " + path_ +
                          ": another process is writing it (a second logger on the same file?); left as it is");
    }
    // ENOLCK, EOPNOTSUPP: a file system without locks (some network shares) records unguarded.
  }
  if (options_.overwrite && ::ftruncate(fd_, 0) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    throw LogWriteError("cannot empty log " + path_ + " to overwrite it: " + std::strerror(error));
  }
}

LogWriter::~LogWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void LogWriter::fail(const std::string& what, int error) {
  failed_ = true;
  // Drop any partial event so readers see a clean end; shrinking a file
  // needs no space, so this works on a full disk.
  if (fd_ >= 0 && ::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0) {
    const int trunc_error = errno;
    throw LogWriteError(what + " " + path_ + ": " + std::strerror(error) +
                        "; cutting it back to its last whole event also failed: " + std::strerror(trunc_error));
  }
  throw LogWriteError(what + " " + path_ + ": " + std::strerror(error) + " (the file holds " + std::to_string(events_) +
                      " whole events, " + std::to_string(bytes_) + " bytes)");
}

void LogWriter::write(std::string_view channel, int64_t timestamp, const void* data, size_t size) {
  if (fd_ < 0 || failed_) throw LogWriteError("log " + path_ + " is closed after an earlier error");
  if (channel.empty() || channel.size() > kMaxChannelBytes || size > kMaxDataBytes)
    throw LogWriteError("cannot log a " + std::to_string(size) + "-byte message on channel '" + std::string(channel) +
                        "': outside the log format's limits");
  EventHeader header;
  header.event_number = events_;
  header.timestamp = timestamp;
  header.channel_bytes = static_cast<uint32_t>(channel.size());
  header.data_bytes = static_cast<uint32_t>(size);
  const auto head = encode_header(header);
  iovec parts[3] = {{const_cast<uint8_t*>(head.data()), head.size()},
                    {const_cast<char*>(channel.data()), channel.size()},
                    {const_cast<void*>(data), size}};
  iovec* next = parts;
  int left = 3;
  uint64_t done = 0;
  while (left > 0) {
    const ssize_t n = ::writev(fd_, next, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write to", errno);
    }
    // Short writes happen as the disk fills; continue where it stopped.
    auto remaining = static_cast<size_t>(n);
    done += remaining;
    while (left > 0 && remaining >= next->iov_len) {
      remaining -= next->iov_len;
      ++next;
      --left;
    }
    if (left > 0) {
      next->iov_base = static_cast<uint8_t*>(next->iov_base) + remaining;
      next->iov_len -= remaining;
    }
  }
  bytes_ += done;
  ++events_;
  if (options_.writeback_chunk_bytes > 0 && bytes_ - written_back_ >= options_.writeback_chunk_bytes)
    write_back(bytes_);
}

// Starts writing [written_back_, upto) to the disk, then waits for the
// chunk before it and drops that from the page cache: the disk works on
// one chunk while the next one is being filled.
void LogWriter::write_back(uint64_t upto) {
  const auto start = static_cast<off64_t>(written_back_);
  if (::sync_file_range(fd_, start, static_cast<off64_t>(upto) - start, SYNC_FILE_RANGE_WRITE) != 0 && errno == EIO)
    fail("I/O error writing", errno);
  if (written_back_ > dropped_) {
    const auto from = static_cast<off64_t>(dropped_);
    const unsigned wait_all = SYNC_FILE_RANGE_WAIT_BEFORE | SYNC_FILE_RANGE_WRITE | SYNC_FILE_RANGE_WAIT_AFTER;
    if (::sync_file_range(fd_, from, start - from, wait_all) != 0 && errno == EIO) fail("I/O error writing", errno);
    ::posix_fadvise(fd_, from, start - from, POSIX_FADV_DONTNEED);
    dropped_ = written_back_;
  }
  written_back_ = upto;
}

bool LogWriter::deleted() const {
  struct stat st {};
  return fd_ >= 0 && fstat(fd_, &st) == 0 && st.st_nlink == 0;
}

void LogWriter::close() {
  if (fd_ < 0) return;
  const int fd = fd_;
  fd_ = -1;
  const bool synced = ::fdatasync(fd) == 0 || errno == EINVAL;  // EINVAL: no sync support (pipes, some fs)
  const int sync_error = errno;
  const bool closed = ::close(fd) == 0;
  if (!synced) throw LogWriteError("cannot sync " + path_ + " to disk: " + std::strerror(sync_error));
  if (!closed) throw LogWriteError("cannot close " + path_ + ": " + std::strerror(errno));
}

}  // namespace ivoa::logio
