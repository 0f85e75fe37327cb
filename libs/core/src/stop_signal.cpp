#include "ivoa/core/stop_signal.hpp"

#include <atomic>
#include <csignal>
#include <initializer_list>

namespace ivoa {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};

extern "C" void on_stop_signal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}

}  // namespace

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // SIGHUP too: a process run by hand whose terminal or ssh session closes
  // must drain and close what it records, not die with it queued.
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
  // A reader that goes away (e.g. `| head`) must not kill a process mid-write.
  std::signal(SIGPIPE, SIG_IGN);
}

bool stop_requested() { return g_stop.load(); }
void request_stop() { g_stop.store(true); }
int stop_signal() { return g_signal.load(); }

}  // namespace ivoa
