#include "ivoa/launcher/script_runner.hpp"

namespace ivoa::launcher {

ScriptRunner::ScriptRunner(std::vector<ScriptStep> steps, Supervisor& supervisor, EventHandler on_event,
                           ReadyCheck ready, std::chrono::milliseconds say_waiting_after)
    : steps_(std::move(steps)),
      supervisor_(supervisor),
      on_event_(std::move(on_event)),
      ready_(std::move(ready)),
      say_waiting_after_(say_waiting_after) {}

std::vector<std::string> ScriptRunner::targets(const ScriptStep& step) const {
  std::vector<std::string> out;
  for (const auto& s : supervisor_.statuses()) {
    const bool match = step.target_kind == TargetKind::kEverything ||
                       (step.target_kind == TargetKind::kCommand && s.name == step.target) ||
                       (step.target_kind == TargetKind::kGroup &&
                        (s.group == step.target || s.group.rfind(step.target + "/", 0) == 0));
    if (match) out.push_back(s.name);
  }
  return out;
}

bool ScriptRunner::satisfied(const std::vector<std::string>& names, const std::string& status) const {
  for (const auto& name : names) {
    const RunState s = supervisor_.status(name).state;
    if (status == "running" && (s == RunState::kIdle || (ready_ && !ready_(name)))) return false;
    if (status == "stopped" && s != RunState::kStopped && s != RunState::kIdle) return false;
  }
  return true;
}

void ScriptRunner::apply(const ScriptStep& step, const std::vector<std::string>& names) {
  for (const auto& name : names) {
    if (step.action == StepAction::kStart) supervisor_.start(name);
    else if (step.action == StepAction::kStop) supervisor_.stop(name);
    else if (step.action == StepAction::kRestart) supervisor_.restart(name);
  }
}

void ScriptRunner::say_still_waiting(const ScriptStep& step, const std::vector<std::string>& names) {
  if (said_waiting_ || Clock::now() - wait_started_ < say_waiting_after_) return;
  said_waiting_ = true;
  std::string states;
  for (const auto& name : names)
    states += (states.empty() ? "" : ", ") + name + " " + to_string(supervisor_.status(name).state);
  const auto waited = std::chrono::duration_cast<std::chrono::seconds>(Clock::now() - wait_started_).count();
  on_event_("script", "line " + std::to_string(step.line) + ": still waiting after " + std::to_string(waited) +
                          " s for " +
                          (step.target_kind == TargetKind::kEverything ? "everything" : "\"" + step.target + "\"") +
                          " to be " + step.wait_status + " (" + states + ")");
}

void ScriptRunner::advance() {
  while (next_ < steps_.size()) {
    const ScriptStep& step = steps_[next_];
    if (step.action == StepAction::kWaitMs) {
      if (!waiting_) {
        waiting_ = true;
        wait_until_ = Clock::now() + std::chrono::microseconds(static_cast<int64_t>(step.wait_ms * 1000));
      }
      if (Clock::now() < wait_until_) return;
    } else {
      const auto names = targets(step);
      if (!waiting_) {
        if (names.empty() && step.target_kind != TargetKind::kEverything)
          on_event_(
              "script",
              "line " + std::to_string(step.line) + ": \"" + step.target +
                  "\" has no command selected here (another --host's, or left out by --group or --skip); step skipped");
        apply(step, names);
        waiting_ = true;
        said_waiting_ = false;
        wait_started_ = Clock::now();
      }
      if (!step.wait_status.empty() && !satisfied(names, step.wait_status)) {
        say_still_waiting(step, names);
        return;
      }
    }
    waiting_ = false;
    ++next_;
  }
}

}  // namespace ivoa::launcher
