#include "ivoa/core/file_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>

namespace ivoa {
namespace {

struct LockFile {
  int fd = -1;
  bool writable = false;
};

// A lock file another user left (a shared folder) or on a read-only mount
// can still be locked through a read-only descriptor: only the pid is not
// written. A link is refused rather than followed: the pid would be written
// into whatever it points to.
LockFile open_lock_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd >= 0) return {fd, true};
  const int error = errno;
  if (error == EACCES || error == EROFS || error == EPERM) {
    const int read_only = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (read_only >= 0) return {read_only, false};
  }
  std::string why = std::strerror(error);
  if (error == ELOOP) why += " (a link: the lock file must be a plain file; remove the link)";
  throw FileLockError(path + ": cannot open the lock file: " + why);
}

// Who holds it, for the message of whoever is refused; not needed for the
// lock itself, so a failed write is no error.
void write_pid(const LockFile& file) {
  if (!file.writable) return;
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(file.fd, 0) != 0) return;
  const ssize_t written = ::pwrite(file.fd, pid.data(), pid.size(), 0);
  static_cast<void>(written);
}

// NFS emulates flock with a byte-range lock, which a read-only descriptor
// cannot take (EBADF): as for a share without locks, nothing can be checked.
[[noreturn]] void throw_lock_error(const std::string& path, const LockFile& file, int error) {
  const bool unsupported = error == ENOLCK || error == EOPNOTSUPP || (error == EBADF && !file.writable);
  throw FileLockError(path + ": cannot lock: " + std::strerror(error), unsupported);
}

}  // namespace

FileLock FileLock::wait_for(const std::string& path) {
  const LockFile file = open_lock_file(path);
  int rc;
  while ((rc = ::flock(file.fd, LOCK_EX)) != 0 && errno == EINTR) {
  }
  if (rc != 0) {
    const int error = errno;
    ::close(file.fd);
    throw_lock_error(path, file, error);
  }
  write_pid(file);
  return FileLock(file.fd);
}

std::optional<FileLock> FileLock::try_take(const std::string& path) {
  const LockFile file = open_lock_file(path);
  if (::flock(file.fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(file.fd);
    if (error == EWOULDBLOCK) return std::nullopt;
    throw_lock_error(path, file, error);
  }
  write_pid(file);
  return FileLock(file.fd);
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
  if (!(in >> pid) || pid <= 0) return 0;
  const bool alive = ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
  return alive ? static_cast<pid_t>(pid) : 0;
}

}  // namespace ivoa
