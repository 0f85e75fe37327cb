#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace ivoa {

// Replaces `path` with `bytes`: written to path + ".tmp", then renamed over
// it, so a reader or a process killed part way never sees half a file, and a
// write that fails (a full disk) leaves the old file whole. It guards against
// dying processes and full disks, not power loss (no fsync). On failure:
// false, `error` naming the file and the system's reason, no temporary left.
bool replace_file(const std::string& path, std::string_view bytes, std::string& error);

// Files that only make sense together (a training checkpoint): each staged
// beside its name, then all renamed into place by commit() once every one was
// written. A write that fails (a full disk) leaves the old set whole, and
// whatever was staged and not committed is removed when the set is destroyed.
// The renames themselves are not one step: a process killed between them
// leaves the files staged first new and the rest old, so stage the file that
// says which set it is (a checkpoint's step) last.
class FileSet {
 public:
  FileSet() = default;
  FileSet(const FileSet&) = delete;
  FileSet& operator=(const FileSet&) = delete;
  ~FileSet();

  bool stage(const std::string& path, std::string_view bytes, std::string& error);
  bool commit(std::string& error);

 private:
  std::vector<std::string> staged_;  // final names; their data is in name + ".tmp"
};

}  // namespace ivoa
