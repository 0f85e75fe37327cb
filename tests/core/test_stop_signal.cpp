// The stop handlers: each signal that ends a run by hand only asks the
// process to stop (CTest runs each case in a process of its own, so the
// flag one case sets does not leak into another).
#include <csignal>

#include <gtest/gtest.h>

#include "ivoa/core/stop_signal.hpp"

namespace ivoa {
namespace {

void expect_a_request_to_stop(int sig) {
  install_stop_handlers();
  ASSERT_FALSE(stop_requested());
  std::raise(sig);  // without the handler, the process would end here
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(stop_signal(), sig);
}

TEST(StopSignal, InterruptAsksToStop) { expect_a_request_to_stop(SIGINT); }
TEST(StopSignal, TerminateAsksToStop) { expect_a_request_to_stop(SIGTERM); }
// A closed terminal or ssh session: the logger drains its queue instead of dying with it.
TEST(StopSignal, HangUpAsksToStop) { expect_a_request_to_stop(SIGHUP); }

}  // namespace
}  // namespace ivoa
