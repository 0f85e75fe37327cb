#include "ivoa/core/file_lock.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_rig.hpp"

namespace {

using ivoa::FileLock;
using ivoa::FileLockError;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(FileLock, IsExclusiveAndNamesItsHolderWhileHeld) {
  ivoa::test::TempDir dir;
  const std::string path = dir.file("a.lock");
  {
    std::optional<FileLock> first = FileLock::try_take(path);
    ASSERT_TRUE(first.has_value());
    EXPECT_FALSE(FileLock::try_take(path).has_value());  // another descriptor, even in this process
    EXPECT_EQ(ivoa::file_lock_holder(path), ::getpid());
  }
  EXPECT_TRUE(FileLock::try_take(path).has_value());
}

TEST(FileLock, APidThatNoLongerRunsIsNoHolder) {
  ivoa::test::TempDir dir;
  const std::string path = dir.file("a.lock");
  std::ofstream(path) << "2147483646\n";
  EXPECT_EQ(ivoa::file_lock_holder(path), 0);
  EXPECT_EQ(ivoa::file_lock_holder(dir.file("none.lock")), 0);
}

// The lock file must be a plain file: following a link would write the pid
// into whatever it points to.
TEST(FileLock, ALinkIsRefusedAndNamed) {
  ivoa::test::TempDir dir;
  std::ofstream(dir.file("target")) << "keep\n";
  std::filesystem::create_symlink(dir.file("target"), dir.file("a.lock"));
  try {
    FileLock::try_take(dir.file("a.lock"));
    FAIL() << "locked through a link";
  } catch (const FileLockError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.file("a.lock") + ": cannot open the lock file"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("a link"), std::string::npos) << e.what();
    EXPECT_FALSE(e.unsupported());
  }
  EXPECT_EQ(read_text(dir.file("target")), "keep\n");
}

// Takes the lock at `path` without write access to the file; 0 if it could,
// and while holding it, saw a second taker refused.
int take_without_write_access(const std::string& path) {
  try {
    std::optional<FileLock> lock = FileLock::try_take(path);
    if (!lock) return 1;
    return FileLock::try_take(path).has_value() ? 2 : 0;
  } catch (const FileLockError&) {
    return 3;
  }
}

// A lock file another user left in a shared folder (or one on a read-only
// mount) is locked through a read-only descriptor; only the pid is not
// written. As root the test drops to another user in a child, since root
// may open any file for writing.
TEST(FileLock, ALockFileThatCannotBeWrittenIsStillLocked) {
  ivoa::test::TempDir dir;
  const std::filesystem::path shared = dir.path() / "shared";
  std::filesystem::create_directory(shared);
  ASSERT_EQ(::chmod(dir.path().c_str(), 0755), 0);
  ASSERT_EQ(::chmod(shared.c_str(), 01777), 0);
  const std::string path = (shared / "a.lock").string();
  std::ofstream(path) << "12345\n";
  ASSERT_EQ(::chmod(path.c_str(), 0444), 0);
  if (::geteuid() != 0) {
    EXPECT_EQ(take_without_write_access(path), 0);
  } else {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      if (::setresgid(65534, 65534, 65534) != 0 || ::setresuid(65534, 65534, 65534) != 0) ::_exit(4);
      ::_exit(take_without_write_access(path));
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "1: refused, 2: not exclusive, 3: error, 4: could not drop root";
  }
  EXPECT_EQ(read_text(path), "12345\n");
}

}  // namespace
