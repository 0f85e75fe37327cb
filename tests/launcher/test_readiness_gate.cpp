// When a script's wait "running" lets an ivoa program's consumers count as
// started: only once they have announced themselves in this run (or after
// the timeout, said once); other commands as soon as they exist.
#include <gtest/gtest.h>

#include "ivoa/launcher/script_runner.hpp"
#include "readiness_gate.hpp"

namespace ivoa::launcher {
namespace {

using Clock = std::chrono::steady_clock;

LaunchCommand command(const std::string& name, const std::string& shell) {
  LaunchCommand c;
  c.spec.name = name;
  c.spec.exec = c.shell_command = shell;
  return c;
}

CommandStatus running(const std::string& name, double uptime_s, int pid = 100) {
  CommandStatus s;
  s.name = name;
  s.state = RunState::kRunning;
  s.uptime_s = uptime_s;
  s.pid = pid;
  return s;
}

HeartbeatMonitor::Latest heard(double seconds_ago, Clock::time_point now) {
  HeartbeatMonitor::Latest h;
  h.received = now - std::chrono::milliseconds(static_cast<int64_t>(seconds_ago * 1000));
  return h;
}

struct GateTest : ::testing::Test {
  std::vector<std::string> events;
  ReadinessGate gate{
      {command("detector", "/opt/ivoa/bin/ivoa-stereo-detector --model jppc"),
       command("late", "sleep 2; exec ${IVOA_BIN}/ivoa-depth-monitor"),
       command("player", "lcm-logplayer --speed=1 session.lcmlog")},
      10.0,
      [this](const std::string& name, const std::string& event) { events.push_back(name + ": " + event); }};
  Clock::time_point now = Clock::now();
};

TEST(RunsAnnouncingProgram, FindsAnIvoaProcessAnywhereInTheCommandLine) {
  EXPECT_TRUE(runs_announcing_program("/build/bin/ivoa-stereo-detector --model jppc"));
  EXPECT_TRUE(runs_announcing_program("ivoa-logger logs/x.lcmlog"));
  EXPECT_TRUE(runs_announcing_program("sleep 2; exec '/build/bin/ivoa-viewer' --every 1"));
  EXPECT_TRUE(runs_announcing_program("LCM_DEFAULT_URL=udpm://x ivoa-depth-monitor"));
  EXPECT_TRUE(runs_announcing_program("cd /tmp && ivoa-logger x"));
  EXPECT_FALSE(runs_announcing_program("lcm-logplayer --speed=1 logs/ivoa-session.lcmlog"));
  EXPECT_FALSE(runs_announcing_program("echo ivoa-stereo-detector"));
  EXPECT_FALSE(runs_announcing_program("cat logs/a | lcm-logplayer -e ivoa-x"));
  EXPECT_FALSE(runs_announcing_program("/opt/bin/my-ivoa-tool"));
  EXPECT_FALSE(runs_announcing_program(""));
  // ivoa programs that send no heartbeat are not waited for.
  EXPECT_FALSE(runs_announcing_program("build/bin/ivoa-lcm-stats --expect STEREO_IMAGES"));
  EXPECT_FALSE(runs_announcing_program("exec ivoa-fake-gige-rig --genicam rig.xml"));
  EXPECT_TRUE(runs_announcing_program("ivoa-log-play logs/x.lcmlog"));
}

TEST_F(GateTest, AnIvoaProgramIsReadyOnceItsHeartbeatOfThisRunArrives) {
  EXPECT_FALSE(gate.ready(running("detector", 1.0), std::nullopt, now));
  EXPECT_FALSE(gate.ready(running("late", 2.5), std::nullopt, now));
  EXPECT_TRUE(gate.ready(running("detector", 1.0), heard(0.2, now), now));
  EXPECT_TRUE(gate.ready(running("late", 2.5), heard(0.1, now), now));
  EXPECT_TRUE(events.empty());
}

TEST_F(GateTest, AHeartbeatFromBeforeARestartDoesNotCount) {
  EXPECT_FALSE(gate.ready(running("detector", 1.0, 101), heard(3.0, now), now));
}

TEST_F(GateTest, OtherCommandsAndCommandsNotRunningDoNotWait) {
  EXPECT_TRUE(gate.ready(running("player", 0.0), std::nullopt, now));
  CommandStatus ended = running("detector", 0.0);
  ended.state = RunState::kStopped;
  EXPECT_TRUE(gate.ready(ended, std::nullopt, now));
  ended.state = RunState::kRespawning;
  EXPECT_TRUE(gate.ready(ended, std::nullopt, now));
}

TEST_F(GateTest, AfterTheTimeoutTheScriptGoesOnAndSaysSoOncePerRun) {
  EXPECT_FALSE(gate.ready(running("detector", 9.9), std::nullopt, now));
  EXPECT_TRUE(gate.ready(running("detector", 10.0), std::nullopt, now));
  EXPECT_TRUE(gate.ready(running("detector", 11.0), std::nullopt, now));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], "detector: no heartbeat within 10 s of starting; the script goes on without it");
  EXPECT_TRUE(gate.ready(running("detector", 12.0, 102), std::nullopt, now));  // a new run says it again
  EXPECT_EQ(events.size(), 2u);
}

TEST(ReadinessGate, ATimeoutOfZeroNeverWaits) {
  ReadinessGate gate({command("detector", "ivoa-stereo-detector")}, 0.0, [](const std::string&, const std::string&) {});
  EXPECT_TRUE(gate.ready(running("detector", 0.0), std::nullopt));
}

TEST(ScriptRunnerReadiness, AWaitForRunningHoldsTheNextStepUntilTheCommandIsReady) {
  const auto quiet = [](const std::string&, const std::string&) {};
  Supervisor supervisor({command("consumer", "sleep 30"), command("source", "sleep 30")}, SupervisorOptions{}, quiet,
                        quiet);
  ScriptStep start_consumer{StepAction::kStart, TargetKind::kCommand, "consumer", "running", 0, 1};
  ScriptStep start_source{StepAction::kStart, TargetKind::kCommand, "source", "", 0, 2};
  bool consumer_ready = false;
  ScriptRunner script({start_consumer, start_source}, supervisor, quiet,
                      [&](const std::string& name) { return name != "consumer" || consumer_ready; });
  script.advance();
  script.advance();
  EXPECT_EQ(supervisor.status("consumer").state, RunState::kRunning);
  EXPECT_EQ(supervisor.status("source").state, RunState::kIdle);
  EXPECT_FALSE(script.done());
  consumer_ready = true;
  script.advance();
  EXPECT_EQ(supervisor.status("source").state, RunState::kRunning);
  EXPECT_TRUE(script.done());
  supervisor.kill_all();
  for (int i = 0; i < 100 && supervisor.busy(); ++i) supervisor.step(50);
}

// A wait that does not hold is said once, with the states it waits on.
TEST(ScriptRunnerReadiness, AWaitThatDoesNotHoldIsSaidOnce) {
  const auto quiet = [](const std::string&, const std::string&) {};
  std::vector<std::string> events;
  Supervisor supervisor({command("consumer", "sleep 30")}, SupervisorOptions{}, quiet, quiet);
  ScriptStep start_consumer{StepAction::kStart, TargetKind::kCommand, "consumer", "running", 0, 7};
  ScriptRunner script(
      {start_consumer}, supervisor,
      [&](const std::string& who, const std::string& event) { events.push_back(who + ": " + event); },
      [](const std::string&) { return false; }, std::chrono::milliseconds(0));
  script.advance();
  script.advance();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], "script: line 7: still waiting after 0 s for \"consumer\" to be running (consumer running)");
  EXPECT_FALSE(script.done());
  supervisor.kill_all();
  for (int i = 0; i < 100 && supervisor.busy(); ++i) supervisor.step(50);
}

}  // namespace
}  // namespace ivoa::launcher
