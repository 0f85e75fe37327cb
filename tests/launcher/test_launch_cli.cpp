// ivoa-launch as a user runs it: --duration, --once, --until, --script,
// --status-file, --list, exit codes, configuration errors, SIGTERM.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/launcher/launcher.hpp"
#include "test_rig.hpp"

extern char** environ;

namespace {

using ivoa::test::read_file;

using Result = ivoa::test::CommandResult;

// Runs ivoa-launch (bounded by timeout(1)) with stdout and stderr captured.
Result launch(const std::string& args) {
  return ivoa::test::run_command("timeout 60 " IVOA_LAUNCH_EXE " --lcm-url none --log-level warn " + args);
}

std::string write_file(const ivoa::test::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(LaunchCli, DurationStopsEverythingAndWritesTheStatus) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "d.pmd", R"(
group "g" {
  cmd "greeter" { exec = "echo hello ${WHO}; sleep 30"; }
  cmd "sleeper" { exec = "sleep 30"; auto_respawn = "true"; stop_signal = 15; }
}
)");
  const auto status = dir.file("status.json");
  const auto start = std::chrono::steady_clock::now();
  const Result r = launch(config + " --set WHO=world --duration 1 --status-file " + status);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(took, 20.0);
  EXPECT_TRUE(contains(r.output, "[greeter] hello world")) << r.output;
  const std::string json = read_file(status);
  EXPECT_TRUE(contains(json, "\"end_reason\": \"--duration reached\"")) << json;
  EXPECT_TRUE(
      contains(json, "\"name\": \"sleeper\", \"group\": \"g\", \"host\": \"localhost\", \"auto_respawn\": true"))
      << json;
  EXPECT_FALSE(contains(json, "\"state\": \"running\"")) << json;
  EXPECT_TRUE(contains(json, "\"exit_signal\": 15")) << json;
}

TEST(LaunchCli, FailedCommandWithoutRespawnGivesExitOne) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "f.pmd", R"(
cmd "broken" { exec = "exit 3"; }
cmd "service" { exec = "sleep 30"; auto_respawn = "true"; }
)");
  const auto status = dir.file("status.json");
  const Result r = launch(config + " --once --grace 0 --duration 30 --status-file " + status);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::string json = read_file(status);
  EXPECT_TRUE(contains(json, "\"end_reason\": \"--once: done\"")) << json;
  EXPECT_TRUE(contains(json, "\"exit_code\": 3, \"exit_signal\": 0, \"failed\": true")) << json;
}

TEST(LaunchCli, RespawningCommandsFailuresDoNotFailTheRun) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "r.pmd", "cmd \"flaky\" { exec = \"exit 2\"; auto_respawn = \"true\"; }\n");
  const auto status = dir.file("status.txt");
  const Result r = launch(config + " --duration 1 --respawn-delay 0.1 --status-file " + status);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string table = read_file(status);
  EXPECT_TRUE(contains(table, "NAME")) << "a .txt status file holds the table";
  EXPECT_TRUE(contains(r.output, "[launcher] flaky: respawning in 0.2 s")) << r.output;
}

TEST(LaunchCli, UntilEndsWhenTheNamedCommandHasEnded) {
  ivoa::test::TempDir dir;
  const auto status = dir.file("s.json");
  const auto once = write_file(dir, "o.pmd", R"(
cmd "session" { exec = "sleep 0.3"; }
cmd "logger" { exec = "sleep 30"; auto_respawn = "true"; }
)");
  const auto start = std::chrono::steady_clock::now();
  const Result r = launch(once + " --until session --grace 0.2 --duration 30 --status-file " + status);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
  EXPECT_TRUE(contains(read_file(status), "\"end_reason\": \"--until: session ended\"")) << read_file(status);
}

// Given a port or a heartbeat channel, the launcher listens there; its
// commands must publish there too, or its table stays empty.
TEST(BusEnvironment, CommandsGetTheHeartbeatChannelAndAUdpmUrlOnly) {
  ivoa::launcher::LauncherOptions options;
  options.status_channel = "ROBOT_B_STATUS";
  options.lcm_url = "udpm://239.255.76.67:7668?ttl=1";
  const std::map<std::string, std::string> both{{"IVOA_STATUS_CHANNEL", "ROBOT_B_STATUS"},
                                                {"LCM_DEFAULT_URL", "udpm://239.255.76.67:7668?ttl=1"}};
  const auto unset = [](const std::string&) { return std::optional<std::string>(); };
  EXPECT_EQ(ivoa::launcher::bus_environment(options, unset), both);
  // the launcher's own bus: each command would get a queue or a file of its own
  for (const char* own : {"none", "memq://", "file:///tmp/run.lcmlog?mode=w"}) {
    options.lcm_url = own;
    EXPECT_EQ(ivoa::launcher::bus_environment(options, unset),
              (std::map<std::string, std::string>{{"IVOA_STATUS_CHANNEL", "ROBOT_B_STATUS"}}))
        << own;
  }
  // no --lcm-url: the launcher listens where the environment says, else on the project's default
  options.lcm_url = "";
  EXPECT_EQ(ivoa::launcher::bus_environment(options, unset).at("LCM_DEFAULT_URL"), ivoa::kProjectDefaultUrl);
  const auto on_7669 = [](const std::string& name) {
    return name == "LCM_DEFAULT_URL" ? std::optional<std::string>("udpm://239.255.76.67:7669") : std::nullopt;
  };
  EXPECT_EQ(ivoa::launcher::bus_environment(options, on_7669).at("LCM_DEFAULT_URL"), "udpm://239.255.76.67:7669");
}

TEST(LaunchCli, CommandsGetTheLaunchersHeartbeatChannelAndKeepTheirLcmUrlForAnInProcessOne) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "e.pmd", R"(
cmd "env" { exec = "echo channel=$IVOA_STATUS_CHANNEL url=$LCM_DEFAULT_URL"; }
)");
  const Result r = ivoa::test::run_command("LCM_DEFAULT_URL=udpm://239.255.76.67:7669 timeout 60 " IVOA_LAUNCH_EXE
                                           " --lcm-url memq:// --once --grace 0 --status-channel ROBOT_B_STATUS " +
                                           config);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "[env] channel=ROBOT_B_STATUS url=udpm://239.255.76.67:7669")) << r.output;
  EXPECT_TRUE(contains(r.output, "--lcm-url memq://: the commands do not get it")) << r.output;
}

TEST(LaunchCli, ABraceVariableForTheBusSettingsIsWhatTheCommandsGet) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "v.pmd", R"(# @default SEED = 1
# @default IVOA_STATUS_CHANNEL = ROBOT_A_STATUS
cmd "env" { exec = "ivoa-stereo-detector --status-channel ${IVOA_STATUS_CHANNEL} --lcm-url ${LCM_DEFAULT_URL} --seed ${SEED}"; }
)");
  // --list expands the commands without opening the bus.
  const std::string list =
      "IVOA_STATUS_CHANNEL=FROM_ENVIRONMENT LCM_DEFAULT_URL=udpm://239.255.76.67:7669 " IVOA_LAUNCH_EXE
      " --list --lcm-url udpm://239.255.76.67:7668?ttl=0 --status-channel ROBOT_C_STATUS ";
  const Result r = ivoa::test::run_command(list + "--set SEED=2 --set SEED=3 " + config);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(
      contains(r.output, "--status-channel ROBOT_C_STATUS --lcm-url udpm://239.255.76.67:7668?ttl=0 --seed 3\n"))
      << r.output;  // and the last --set of a name wins
  EXPECT_TRUE(contains(r.output,
                       "v.pmd:2: the default IVOA_STATUS_CHANNEL = ROBOT_A_STATUS is not used: the launcher "
                       "hands its commands IVOA_STATUS_CHANNEL=ROBOT_C_STATUS (--status-channel)"))
      << r.output;

  const Result agreeing = ivoa::test::run_command(list + "--set IVOA_STATUS_CHANNEL=ROBOT_C_STATUS " + config);
  EXPECT_EQ(agreeing.exit_code, 0) << agreeing.output;
  // each --set counts, not only the last of a name
  const Result contradicting = ivoa::test::run_command(
      list + "--set IVOA_STATUS_CHANNEL=PROCESS_STATUS --set IVOA_STATUS_CHANNEL=ROBOT_C_STATUS " + config);
  EXPECT_EQ(contradicting.exit_code, 2) << contradicting.output;
  EXPECT_TRUE(contains(contradicting.output,
                       "--set IVOA_STATUS_CHANNEL=PROCESS_STATUS: the launcher hands its commands "
                       "IVOA_STATUS_CHANNEL=ROBOT_C_STATUS (--status-channel); change it there"))
      << contradicting.output;
}

TEST(LaunchCli, WithoutLcmUrlTheCommandsGetTheUrlTheLauncherListensOn) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "u.pmd", R"(
cmd "env" { exec = "ivoa-stereo-detector --lcm-url ${LCM_DEFAULT_URL}"; }
)");
  const std::string list = "env -u LCM_DEFAULT_URL " IVOA_LAUNCH_EXE " --list ";
  const Result r = ivoa::test::run_command(list + config);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, std::string("--lcm-url ") + ivoa::kProjectDefaultUrl + "\n")) << r.output;
  EXPECT_TRUE(contains(r.output, std::string("LCM_DEFAULT_URL=") + ivoa::kProjectDefaultUrl)) << r.output;
  // the commands would publish on 7668 while the launcher listens on 7667
  const Result elsewhere = ivoa::test::run_command(list + "--set LCM_DEFAULT_URL=udpm://239.255.76.67:7668 " + config);
  EXPECT_EQ(elsewhere.exit_code, 2) << elsewhere.output;
  EXPECT_TRUE(contains(elsewhere.output, "(--lcm-url); change it there")) << elsewhere.output;
}

TEST(LaunchCli, ScriptStartsOnlyWhatItNamesInOrder) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "s.pmd", R"(
group "first" { cmd "a" { exec = "echo a"; } }
group "second" { cmd "b" { exec = "echo b"; } }
cmd "never" { exec = "echo never"; }
script "go" {
  start group "first" wait "running";
  wait cmd "a" status "stopped";
  wait ms 100;
  start cmd "b" wait "stopped";
}
)");
  const auto status = dir.file("s.json");
  const Result r = launch(config + " --script go --duration 20 --status-file " + status);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto a = r.output.find("[a] a"), b = r.output.find("[b] b");
  ASSERT_NE(a, std::string::npos) << r.output;
  ASSERT_NE(b, std::string::npos) << r.output;
  EXPECT_LT(a, b);
  EXPECT_FALSE(contains(r.output, "[never]"));
  const std::string json = read_file(status);
  EXPECT_TRUE(contains(json,
                       "\"name\": \"never\", \"group\": \"\", \"host\": \"localhost\", \"auto_respawn\": false, "
                       "\"pid\": 0, \"state\": \"idle\""))
      << json;
  EXPECT_TRUE(contains(json, "\"end_reason\": \"every command has ended\"")) << json;
}

// A producer that takes half a second to stop and a logger: the file's
// "stop" script stops the producer first and waits for it, so the logger
// outlives it; with --stop-script "" both get the signal at once and the
// logger is gone first.
TEST(LaunchCli, TheStopScriptStopsTheProducerBeforeTheLogger) {
  ivoa::test::TempDir dir;
  const auto order = dir.file("order.txt");
  const auto config = write_file(dir, "stop.pmd", R"(
cmd "logger" { exec = "trap 'echo logger >> ${ORDER}; exit 0' INT; while true; do sleep 0.05; done"; }
cmd "producer" { exec = "trap 'sleep 0.5; echo producer >> ${ORDER}; exit 0' INT; while true; do sleep 0.05; done"; }
script "stop" {
  stop cmd "producer" wait "stopped";
  stop cmd "logger" wait "stopped";
}
)");
  Result r = launch(config + " --set ORDER=" + order + " --duration 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_file(order), "producer\nlogger\n") << r.output;
  EXPECT_TRUE(contains(r.output, "running script \"stop\"")) << r.output;

  std::remove(order.c_str());
  r = launch(config + " --set ORDER=" + order + " --duration 1 --stop-script ''");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_file(order), "logger\nproducer\n") << r.output;

  r = launch(config + " --set ORDER=" + order + " --duration 1 --stop-script shutdown");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "--stop-script shutdown: no such script")) << r.output;
}

TEST(LaunchCli, ConfigurationErrorsNameFileAndLineAndExitTwo) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "bad.pmd", "cmd \"a\" {\n  exec = \"x\"\n}\n");
  Result r = launch(config);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, config + ":3: expected ';'")) << r.output;

  const auto unset = write_file(dir, "unset.pmd", "\ncmd \"a\" { exec = \"run ${IVOA_TEST_SURELY_UNSET}\"; }\n");
  r = launch(unset);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, unset + ":2: cmd \"a\": variable ${IVOA_TEST_SURELY_UNSET} is not set")) << r.output;

  r = launch(unset + " --group nope");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.output, "no group \"nope\"")) << r.output;
}

// What would only fail after the run (an output path that cannot be
// written), or silently (a --set of a name the file does not use), is said
// before anything starts.
TEST(LaunchCli, OutputPathsAndSetsAreCheckedBeforeTheRun) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "o.pmd", "# @default RATE = 5\ncmd \"a\" { exec = \"echo ${RATE}\"; }\n");
  const auto file = write_file(dir, "plain_file", "x");
  Result r = launch(config + " --output-dir " + file + " --duration 30");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_TRUE(contains(r.output, "--output-dir " + file + ": cannot create the folder")) << r.output;
  EXPECT_FALSE(contains(r.output, "[a] 5")) << "the command ran: " << r.output;
  r = launch(config + " --status-file " + dir.file("missing/status.json") + " --duration 30");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_TRUE(contains(r.output, "missing/status.json: cannot write: No such file or directory")) << r.output;
  r = launch(config + " --duration 1e30");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = launch(config + " --set RATES=9 --duration 0.2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "--set RATES=9: " + config + " has no ${RATES} (its variables: RATE)")) << r.output;
}

TEST(LaunchCli, ListShowsTheCommandsForTheHostExpanded) {
  ivoa::test::TempDir dir;
  const auto config = write_file(dir, "l.pmd", R"(# @default RATE = 5
group "robot" {
  cmd "camera" { exec = "cam --rate ${RATE}"; host = "robot1"; auto_respawn = "true"; }
  cmd "local" { exec = "loc"; }
}
)");
  Result r = launch(config + " --list --host robot1 --set RATE=9");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(contains(r.output, "camera [robot] auto_respawn stop_signal 2\n    cam --rate 9")) << r.output;
  EXPECT_TRUE(contains(r.output, "(other host) local (localhost)")) << r.output;
  r = launch(config + " --list --status-channel ROBOT_B_STATUS");
  EXPECT_TRUE(contains(r.output, "    loc\n")) << r.output;
  EXPECT_FALSE(contains(r.output, "cam --rate")) << r.output;
  EXPECT_TRUE(contains(r.output, "in every command's environment: IVOA_STATUS_CHANNEL=ROBOT_B_STATUS\n")) << r.output;
}

// ivoa-launch in the background, its stdout and stderr in `out`; its stdin
// closed if `close_stdin`, as a service manager or `<&-` may start it.
pid_t spawn_launcher(const std::string& config, const std::string& out, bool close_stdin = false) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (close_stdin) posix_spawn_file_actions_addclose(&actions, STDIN_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  const char* argv[] = {IVOA_LAUNCH_EXE, config.c_str(), "--lcm-url", "none", "--duration", "60", nullptr};
  pid_t pid = 0;
  const int err = posix_spawn(&pid, IVOA_LAUNCH_EXE, &actions, nullptr, const_cast<char**>(argv), environ);
  posix_spawn_file_actions_destroy(&actions);
  return err == 0 ? pid : -1;
}

// The pid a command wrote to `path`, waiting up to 10 s; 0 if none.
int wait_for_pid_file(const std::string& path) {
  int pid = 0;
  for (int i = 0; i < 200 && pid == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::ifstream(path) >> pid;
  }
  return pid;
}

// The launcher's wait status, or -1 (after killing it) if it has not exited within `limit_s`.
int wait_for_exit(pid_t pid, double limit_s) {
  int status = 0;
  for (int i = 0; i < limit_s * 20; ++i) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

TEST(LaunchCli, SigtermStopsEveryCommandAndExitsCleanly) {
  ivoa::test::TempDir dir;
  const std::string pid_file = dir.file("worker.pid");
  const auto config =
      write_file(dir, "t.pmd",
                 "cmd \"worker\" { exec = \"echo $$ > " + pid_file + "; exec sleep 30\"; auto_respawn = \"true\"; }\n");
  const std::string out = dir.file("out.txt");
  const pid_t launcher = spawn_launcher(config, out);
  ASSERT_GT(launcher, 0);
  const int worker = wait_for_pid_file(pid_file);
  ASSERT_GT(worker, 0) << "the command never started";
  kill(launcher, SIGTERM);
  const int status = wait_for_exit(launcher, 10);
  ASSERT_NE(status, -1) << "ivoa-launch did not exit within 10 s of SIGTERM";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_NE(kill(worker, 0), 0) << "the command outlived the launcher";
  EXPECT_TRUE(contains(read_file(out), "stopping (signal 15)")) << read_file(out);
}

TEST(LaunchCli, SecondStopSignalKillsAtOnce) {
  ivoa::test::TempDir dir;
  const std::string pid_file = dir.file("stubborn.pid");
  // Ignores the stop signal and would be given 60 s before SIGKILL.
  const auto config = write_file(dir, "k.pmd",
                                 "cmd \"stubborn\" { exec = \"trap '' INT TERM; echo $$ > " + pid_file +
                                     "; sleep 60\"; stop_time_allowed = 60; }\n");
  const std::string out = dir.file("out.txt");
  const pid_t launcher = spawn_launcher(config, out);
  ASSERT_GT(launcher, 0);
  const int stubborn = wait_for_pid_file(pid_file);
  ASSERT_GT(stubborn, 0);
  kill(launcher, SIGINT);
  for (int i = 0; i < 100 && !contains(read_file(out), "stopping (signal 2)"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(launcher, SIGINT);
  const int status = wait_for_exit(launcher, 20);
  ASSERT_NE(status, -1) << "a second Ctrl-C must not wait for stop_time_allowed";
  EXPECT_TRUE(contains(read_file(out), "second stop signal: SIGKILL to every command")) << read_file(out);
  EXPECT_NE(kill(stubborn, 0), 0);
}

TEST(LaunchCli, SigkilledLauncherStillStopsCompoundCommandsChildren) {
  ivoa::test::TempDir dir;
  const std::string fg_file = dir.file("fg.pid"), bg_file = dir.file("bg.pid");
  // The kernel's death signal reaches only each command's shell. The
  // foreground child stops on the stop signal (SIGKILL would come only
  // after 30 s); the background one ignores SIGINT, as a non-interactive
  // shell's background jobs do, and needs the SIGKILL after 1 s.
  const auto config = write_file(dir, "c.pmd",
                                 "cmd \"fg\" { exec = \"sh -c 'echo $$ > " + fg_file +
                                     "; exec sleep 300'; true\"; stop_time_allowed = 30; }\n"
                                     "cmd \"bg\" { exec = \"sleep 300 & echo $! > " +
                                     bg_file + "; wait\"; stop_time_allowed = 1; }\n");
  const std::string out = dir.file("out.txt");
  // stdin closed: the watchdog's pipe must not land on descriptor 0.
  const pid_t launcher = spawn_launcher(config, out, true);
  ASSERT_GT(launcher, 0);
  const int fg = wait_for_pid_file(fg_file), bg = wait_for_pid_file(bg_file);
  ASSERT_GT(fg, 0);
  ASSERT_GT(bg, 0);
  kill(launcher, SIGKILL);
  waitpid(launcher, nullptr, 0);
  const bool ended = ivoa::test::processes_end_within({fg, bg}, 15);
  for (const int pid : {fg, bg})  // only what still runs: an ended pid may already be another process's
    if (!ivoa::test::process_has_ended(pid)) kill(pid, SIGKILL);
  EXPECT_TRUE(ended) << "a compound command's children outlived the SIGKILLed launcher: fg "
                     << (ivoa::test::process_has_ended(fg) ? "ended" : "running") << ", bg "
                     << (ivoa::test::process_has_ended(bg) ? "ended" : "running");
  for (int i = 0; i < 100 && !contains(read_file(out), "SIGKILL"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(contains(read_file(out), "the watchdog stops 2 process group(s)")) << read_file(out);
}

}  // namespace
