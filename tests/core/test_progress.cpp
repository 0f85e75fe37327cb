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
  // ivoa-train --steps 99999999999 said "ETA -596523h-14m": an int of seconds overflowed.
  Progress long_run("steps", 1e15, "steps");
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  const std::string far = long_run.line(1, "");
  EXPECT_EQ(far.find("ETA -"), std::string::npos) << far;
  EXPECT_NE(far.find("ETA over 10^6 h"), std::string::npos) << far;
}

}  // namespace
}  // namespace ivoa
