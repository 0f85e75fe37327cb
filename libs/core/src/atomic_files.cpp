#include "ivoa/core/atomic_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace ivoa {
namespace {

std::string temporary_of(const std::string& path) { return path + ".tmp"; }

// `what` and the system's reason (an errno value taken before anything could change it).
std::string system_error(const std::string& what, int error_number) {
  return what + " (" + std::strerror(error_number) + ")";
}

// All of `bytes` into `path` (created or truncated); false with `reason` set.
bool write_whole_file(const std::string& path, std::string_view bytes, std::string& reason) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int error_number = errno;
    reason = system_error("cannot create " + path, error_number);
    return false;
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error_number = n == 0 ? ENOSPC : errno;
      reason = system_error("cannot write", error_number);
      ::close(fd);
      return false;
    }
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) {  // NFS and some file systems report a full disk only here
    const int error_number = errno;
    reason = system_error("cannot write", error_number);
    return false;
  }
  return true;
}

}  // namespace

bool replace_file(const std::string& path, std::string_view bytes, std::string& error) {
  FileSet one;
  return one.stage(path, bytes, error) && one.commit(error);
}

FileSet::~FileSet() {
  for (const auto& path : staged_) std::remove(temporary_of(path).c_str());
}

bool FileSet::stage(const std::string& path, std::string_view bytes, std::string& error) {
  // The rename would put a regular file in a device's or pipe's place (run
  // as root, --out /dev/full replaced the device node).
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    error = path + ": not a regular file (a device, pipe or folder is not replaced); name a file";
    return false;
  }
  staged_.push_back(path);
  std::string reason;
  if (write_whole_file(temporary_of(path), bytes, reason)) return true;
  error = path + ": " + reason + "; the previous file, if any, is kept";
  return false;
}

bool FileSet::commit(std::string& error) {
  for (size_t k = 0; k < staged_.size(); ++k) {
    if (std::rename(temporary_of(staged_[k]).c_str(), staged_[k].c_str()) != 0) {
      const int error_number = errno;
      error = staged_[k] + ": " + system_error("cannot rename the new file into place", error_number);
      staged_.erase(staged_.begin(), staged_.begin() + static_cast<std::ptrdiff_t>(k));
      return false;
    }
  }
  staged_.clear();
  return true;
}

}  // namespace ivoa
