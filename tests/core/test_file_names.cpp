// Numbered file names: how a respawned recorder avoids the last one's file.
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "ivoa/core/file_names.hpp"

namespace ivoa {
namespace {

TEST(NumberedFileName, GoesBeforeTheExtensionAndKeepsTheFolder) {
  EXPECT_EQ(numbered_file_name("logs/clip.oni", 0), "logs/clip.oni");
  EXPECT_EQ(numbered_file_name("logs/clip.oni", 2), "logs/clip-2.oni");
  EXPECT_EQ(numbered_file_name("run.2026.lcmlog", 1), "run.2026-1.lcmlog");
  EXPECT_EQ(numbered_file_name("session", 12), "session-12");
  EXPECT_EQ(numbered_file_name("/data/logs/a.b/session", 3), "/data/logs/a.b/session-3");
}

TEST(FirstFreeNumberedName, SkipsNamesInUseAndGivesUpAfterTheLast) {
  std::set<std::string> used = {"a.lcmlog", "a-1.lcmlog"};
  const auto take = [&used](const std::string& name) { return used.insert(name).second; };
  EXPECT_EQ(first_free_numbered_name("a.lcmlog", 3, take), "a-2.lcmlog");
  EXPECT_EQ(first_free_numbered_name("a.lcmlog", 3, take), "a-3.lcmlog");
  EXPECT_EQ(first_free_numbered_name("a.lcmlog", 3, take), std::nullopt);
  EXPECT_EQ(first_free_numbered_name("b.lcmlog", 3, take), "b.lcmlog");
}

}  // namespace
}  // namespace ivoa
