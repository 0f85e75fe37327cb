// The progress line: counts, rate, and an ETA only once there is a rate to trust.
#include <chrono>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "ivoa/core/progress.hpp"

namespace ivoa {
namespace {

TEST(Progress, GivesNoEtaFromTheFirstMomentsAndOneAfter) {
  Progress progress("session s", 43, "MB");
  const std::string early = progress.line(0.001, "");
  EXPECT_NE(early.find("session s: 0/43 MB (0%)"), std::string::npos) << early;
  EXPECT_NE(early.find("ETA ?"), std::string::npos) << early;
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // past the first second, not a timing check
  const std::string later = progress.line(21, "96 frames");
  EXPECT_NE(later.find("21/43 MB (49%)"), std::string::npos) << later;
  EXPECT_EQ(later.find("ETA ?"), std::string::npos) << later;
  EXPECT_NE(later.find(", 96 frames"), std::string::npos) << later;
}

}  // namespace
}  // namespace ivoa
