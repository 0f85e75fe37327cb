// The small file outputs every tool shares (--json, --ready-file).
#include <string>

#include <gtest/gtest.h>

#include "ivoa/core/process.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

TEST(WriteTextFile, WritesTheTextOrSaysItCannot) {
  test::TempDir dir;
  EXPECT_TRUE(write_text_file(dir.file("out.json"), "{\"a\": 1}\n"));
  EXPECT_EQ(test::read_file(dir.file("out.json")), "{\"a\": 1}\n");
  EXPECT_TRUE(write_text_file("", "nothing asked, nothing written"));
  EXPECT_FALSE(write_text_file(dir.file("no_such_folder/out.json"), "x"));
  EXPECT_FALSE(write_text_file("/dev/full", "a full disk is reported, not lost in the buffer"));
}

TEST(WriteReadyFile, CreatesTheFileScriptsWaitFor) {
  test::TempDir dir;
  EXPECT_TRUE(write_ready_file(dir.file("ready")));
  EXPECT_EQ(test::read_file(dir.file("ready")), "ready\n");
  EXPECT_TRUE(write_ready_file(""));
  EXPECT_FALSE(write_ready_file(dir.file("no_such_folder/ready")));
}

}  // namespace
}  // namespace ivoa
