#include "ivoa/core/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>

namespace ivoa {
namespace {

int open_lock_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (fd < 0) throw FileLockError(path + ": cannot open the lock file: " + std::strerror(errno));
  return fd;
}

// Who holds it, for the message of whoever is refused; not needed for the
// lock itself, so a failed write is no error.
void write_pid(int fd) {
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0) return;
  const ssize_t written = ::pwrite(fd, pid.data(), pid.size(), 0);
  static_cast<void>(written);
}

}  // namespace

FileLock FileLock::wait_for(const std::string& path) {
  const int fd = open_lock_file(path);
  int rc;
  while ((rc = ::flock(fd, LOCK_EX)) != 0 && errno == EINTR) {
  }
  if (rc != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw FileLockError(path + ": cannot lock: " + why);
  }
  write_pid(fd);
  return FileLock(fd);
}

std::optional<FileLock> FileLock::try_take(const std::string& path) {
  const int fd = open_lock_file(path);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd);
    if (error == EWOULDBLOCK) return std::nullopt;
    throw FileLockError(path + ": cannot lock: " + std::strerror(error));
  }
  write_pid(fd);
  return FileLock(fd);
}

FileLock::FileLock(FileLock&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}

FileLock& FileLock::operator=(FileLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

pid_t file_lock_holder(const std::string& path) {
  std::ifstream in(path);
  long pid = 0;
  return in >> pid && pid > 0 ? static_cast<pid_t>(pid) : 0;
}

}  // namespace ivoa
