#pragma once
// A process given a log to replay (--lcm-url file://LOG) reads it through
// LCM's own reader, which stops at the first damage with one line and no
// byte offset, losing every event after it, and crashes (SIGSEGV) on an
// event that claims 2^31-1 bytes. Such a log is refused before LCM opens
// it, naming where it is damaged: ivoa-log-play plays it, skipping the damage.
#include <string>

namespace ivoa::logio {

// Why LCM cannot replay the log `lcm_url` names (its damage, by byte
// offset, and what plays it instead); "" if it can, or if the URL replays
// no log (one that does not exist is left to LCM, which says so).
std::string why_lcm_cannot_replay(const std::string& lcm_url);

// Throws BusError (exit code kExitBadInput) with why_lcm_cannot_replay's
// reason, if any: called just before a process starts LCM on `lcm_url`.
void refuse_a_log_lcm_cannot_replay(const std::string& lcm_url);

}  // namespace ivoa::logio
