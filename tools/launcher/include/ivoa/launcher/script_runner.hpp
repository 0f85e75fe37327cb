#pragma once
// Runs a procman script (flattened by flatten_script) against a Supervisor,
// one step at a time, without blocking: advance() does what it can and
// returns at the first wait that is not yet satisfied.
// "running" means every target has been started (and passes the ready
// check, if one is given); "stopped" means none of them runs, stops or
// waits to respawn.
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "ivoa/launcher/config.hpp"
#include "ivoa/launcher/supervisor.hpp"

namespace ivoa::launcher {

class ScriptRunner {
 public:
  // Whether a started command counts as running yet (ivoa-launch: it has
  // announced itself; see readiness_gate.hpp).
  using ReadyCheck = std::function<bool(const std::string& command)>;

  // A wait that has not held after `say_waiting_after` is said (once per
  // step, naming the step, its targets and their states): a script that
  // waits for a command that never gets there does not stall in silence.
  ScriptRunner(std::vector<ScriptStep> steps, Supervisor& supervisor, EventHandler on_event, ReadyCheck ready = nullptr,
               std::chrono::milliseconds say_waiting_after = std::chrono::seconds(30));

  void advance();
  bool done() const { return next_ >= steps_.size(); }

 private:
  using Clock = std::chrono::steady_clock;
  // The selected commands a step's target names (none if they run elsewhere).
  std::vector<std::string> targets(const ScriptStep& step) const;
  bool satisfied(const std::vector<std::string>& names, const std::string& status) const;
  void apply(const ScriptStep& step, const std::vector<std::string>& names);
  void say_still_waiting(const ScriptStep& step, const std::vector<std::string>& names);

  std::vector<ScriptStep> steps_;
  Supervisor& supervisor_;
  EventHandler on_event_;
  ReadyCheck ready_;
  size_t next_ = 0;
  bool waiting_ = false;
  bool said_waiting_ = false;
  Clock::time_point wait_until_, wait_started_;
  std::chrono::milliseconds say_waiting_after_;
};

}  // namespace ivoa::launcher
