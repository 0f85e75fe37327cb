#pragma once
// Clean shutdown on SIGINT, SIGTERM and SIGHUP: handlers only set a flag
// that every loop polls, so each process finishes its current message and
// exits (the logger after writing what it has queued).

namespace ivoa {

void install_stop_handlers();
bool stop_requested();
void request_stop();
// The signal that asked us to stop (0 if none or requested in code).
int stop_signal();

}  // namespace ivoa
