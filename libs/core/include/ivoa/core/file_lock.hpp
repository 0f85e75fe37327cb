#pragma once
// An exclusive flock(2) on a file, held while the object lives; the kernel
// releases it when the process ends, however it ends (a killed or respawned
// process leaves no stale lock). The holder writes its pid into the file so
// that whoever is refused can be told who holds it.
#include <optional>
#include <stdexcept>
#include <string>
#include <sys/types.h>

namespace ivoa {

class FileLockError : public std::runtime_error {
 public:
  FileLockError(const std::string& what, bool unsupported = false)
      : std::runtime_error(what), unsupported_(unsupported) {}
  // The file system cannot lock at all (ENOLCK, EOPNOTSUPP: an NFS or CIFS
  // share without a lock service; NFS given a lock file another user owns),
  // as opposed to this file or folder.
  bool unsupported() const { return unsupported_; }

 private:
  bool unsupported_;
};

class FileLock {
 public:
  // Waits until the lock is free. Throws FileLockError naming the file and
  // why it cannot be locked (a folder that cannot be written, ...).
  static FileLock wait_for(const std::string& path);
  // The lock, or nullopt while another process holds it. Throws
  // FileLockError as wait_for does.
  static std::optional<FileLock> try_take(const std::string& path);

  FileLock(FileLock&& other) noexcept;
  FileLock& operator=(FileLock&& other) noexcept;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock();

 private:
  explicit FileLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

// The pid the holder of the lock at `path` wrote, if that process is alive;
// 0 otherwise. A holder that could only read the file (one another user
// left) wrote none, so a pid is a hint, not proof.
pid_t file_lock_holder(const std::string& path);

}  // namespace ivoa
