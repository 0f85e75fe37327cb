// Files replaced whole or not at all: what keeps a checkpoint, a model or a
// sidecar usable when the disk fills while it is rewritten.
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "ivoa/core/atomic_files.hpp"
#include "file_size_limit.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

TEST(ReplaceFile, WritesANewFileAndReplacesAnOldOne) {
  test::TempDir dir;
  const std::string path = dir.file("a.bin");
  std::string error;
  ASSERT_TRUE(replace_file(path, "first", error)) << error;
  ASSERT_TRUE(replace_file(path, std::string(3, '\0') + "second", error)) << error;
  EXPECT_EQ(test::read_file(path), std::string(3, '\0') + "second");
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(ReplaceFile, AWriteThatFailsKeepsTheOldFileWhole) {
  test::TempDir dir;
  const std::string path = dir.file("model.pt");
  std::string error;
  ASSERT_TRUE(replace_file(path, "the old model", error)) << error;
  {
    const test::FileSizeLimit nearly_full_disk(1000);
    EXPECT_FALSE(replace_file(path, std::string(5000, 'x'), error));
  }
  EXPECT_EQ(test::read_file(path), "the old model");
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  EXPECT_NE(error.find(path + ": cannot write (File too large)"), std::string::npos) << error;
  EXPECT_NE(error.find("the previous file, if any, is kept"), std::string::npos) << error;
}

// Run as root, a --json or --out naming /dev/full had the device node
// replaced by a regular file; a pipe here stands for any such file.
TEST(ReplaceFile, APipeOrDeviceIsRefusedAndLeftInPlace) {
  test::TempDir dir;
  const std::string path = dir.file("pipe");
  ASSERT_EQ(::mkfifo(path.c_str(), 0644), 0);
  std::string error;
  EXPECT_FALSE(replace_file(path, "x", error));
  EXPECT_NE(error.find(path + ": not a regular file"), std::string::npos) << error;
  EXPECT_TRUE(std::filesystem::is_fifo(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(ReplaceFile, AFolderThatIsNotThereIsNamed) {
  test::TempDir dir;
  std::string error;
  EXPECT_FALSE(replace_file(dir.file("no/such/folder/a.bin"), "x", error));
  EXPECT_NE(error.find("cannot create " + dir.file("no/such/folder/a.bin.tmp") + " (No such file or directory)"),
            std::string::npos)
      << error;
}

TEST(FileSet, AFailurePartWayLeavesTheWholeOldSet) {
  test::TempDir dir;
  const std::string a = dir.file("c.model"), b = dir.file("c.optimizer"), step = dir.file("c.step");
  std::string error;
  {
    FileSet old;
    ASSERT_TRUE(old.stage(a, "model 1", error) && old.stage(b, "optimizer 1", error) && old.stage(step, "1", error));
    ASSERT_TRUE(old.commit(error)) << error;
  }
  {
    FileSet next;
    ASSERT_TRUE(next.stage(a, "model 2", error)) << error;
    const test::FileSizeLimit nearly_full_disk(100);
    EXPECT_FALSE(next.stage(b, std::string(500, 'o'), error));  // the set is dropped, not committed
  }
  EXPECT_EQ(test::read_file(a), "model 1");
  EXPECT_EQ(test::read_file(b), "optimizer 1");
  EXPECT_EQ(test::read_file(step), "1");
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
}

}  // namespace
}  // namespace ivoa
