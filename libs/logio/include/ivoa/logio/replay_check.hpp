#pragma once
// A process given a log to replay (--lcm-url file://LOG) reads it through
// LCM's own reader, which stops at the first damage with one line and no
// byte offset, losing every event after it, and crashes (SIGSEGV) on an
// event that claims 2^31-1 bytes. Such a log is refused before LCM opens
// it, naming where it is damaged: ivoa-log-play plays it, skipping the damage.
// A log whose only damage is its last event cut short (the recording
// stopped while writing it) loses nothing else: LCM plays every event
// before the cut and ends there, so it is played, with a warning.
#include <string>

namespace ivoa::logio {

struct ReplayCheck {
  std::string refusal;  // why LCM cannot replay the log, by byte offset; "" if it can
  std::string warning;  // what a replay leaves out (a last event cut short); "" if nothing
};

// Checks the log `lcm_url` replays, if it names one (a log that does not
// exist is left to LCM, which says so).
ReplayCheck check_log_for_replay(const std::string& lcm_url);

// Throws BusError (exit code kExitBadInput) with check_log_for_replay's
// refusal, if any, and warns of what the replay leaves out: called just
// before a process starts LCM on `lcm_url`.
void refuse_a_log_lcm_cannot_replay(const std::string& lcm_url);

// LCM cannot publish into a log it reads: a process given one computes its
// `outputs` (channel names) and counts them as publish_failures. Says so
// once, with the way to see them, if `lcm_url` replays a log; true if so.
bool warn_that_a_replay_publishes_nothing(const std::string& lcm_url, const std::string& outputs);

}  // namespace ivoa::logio
