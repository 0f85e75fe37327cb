// The procman configuration parser: syntax (nested groups, attributes,
// scripts, comments, defaults), and errors that name the file and line.
#include <filesystem>

#include <gtest/gtest.h>

#include "ivoa/launcher/config.hpp"

namespace ivoa::launcher {
namespace {

const char* kExample = R"(# A robot's processes.
# @default SEED = 7
group "0.drivers" {
    cmd "camera" {
        exec = "cam --seed ${SEED} --name \"left cam\"";   # trailing comment
        host = "robot";
        auto_respawn = "true";
        stop_signal = 15;
        stop_time_allowed = 2.5;
    }
    group "inner" {
        cmd "deep" { exec = "sleep 1"; deputy = "laptop"; }
    }
}
cmd "top" {
    exec = "echo top";
    auto_respawn = false;
}
script "start" {
    start group "0.drivers" wait "running";
    wait ms 500;
    run_script "more";
    stop cmd "top" wait "stopped";
}
script "more" {
    restart everything;
    wait cmd "deep" status "stopped";
}
)";

TEST(LauncherConfig, ParsesNestedGroupsAttributesAndDefaults) {
  const Config c = parse_config(kExample, "example.pmd");
  ASSERT_EQ(c.commands.size(), 3u);
  const CommandSpec& camera = *c.find_command("camera");
  EXPECT_EQ(camera.group, "0.drivers");
  EXPECT_EQ(camera.exec, "cam --seed ${SEED} --name \"left cam\"");
  EXPECT_EQ(camera.host, "robot");
  EXPECT_TRUE(camera.auto_respawn);
  EXPECT_EQ(camera.stop_signal, 15);
  EXPECT_DOUBLE_EQ(camera.stop_time_allowed_s, 2.5);
  EXPECT_EQ(camera.line, 4);

  const CommandSpec& deep = *c.find_command("deep");
  EXPECT_EQ(deep.group, "0.drivers/inner");
  EXPECT_EQ(deep.host, "laptop") << "deputy is procman's name for host";
  EXPECT_FALSE(deep.auto_respawn);
  EXPECT_EQ(deep.stop_signal, kDefaultStopSignal);
  EXPECT_DOUBLE_EQ(deep.stop_time_allowed_s, kDefaultStopTimeAllowedS);

  EXPECT_EQ(c.find_command("top")->group, "");
  EXPECT_EQ(c.groups, (std::vector<std::string>{"0.drivers", "0.drivers/inner"}));
  ASSERT_EQ(c.defaults.count("SEED"), 1u);
  EXPECT_EQ(c.defaults.at("SEED").value, "7");
  EXPECT_EQ(c.defaults.at("SEED").line, 2);
}

TEST(LauncherConfig, GroupMembershipIncludesSubgroupsOnly) {
  const Config c = parse_config(kExample, "example.pmd");
  EXPECT_TRUE(in_group(*c.find_command("deep"), "0.drivers"));
  EXPECT_TRUE(in_group(*c.find_command("deep"), "0.drivers/inner"));
  EXPECT_FALSE(in_group(*c.find_command("camera"), "0.drivers/inner"));
  EXPECT_FALSE(in_group(*c.find_command("camera"), "0.driv"));
}

TEST(LauncherConfig, ScriptsAreFlattenedInOrder) {
  const Config c = parse_config(kExample, "example.pmd");
  const auto steps = flatten_script(c, "start");
  ASSERT_EQ(steps.size(), 5u);
  EXPECT_EQ(steps[0].action, StepAction::kStart);
  EXPECT_EQ(steps[0].target_kind, TargetKind::kGroup);
  EXPECT_EQ(steps[0].wait_status, "running");
  EXPECT_EQ(steps[1].action, StepAction::kWaitMs);
  EXPECT_DOUBLE_EQ(steps[1].wait_ms, 500);
  EXPECT_EQ(steps[2].action, StepAction::kRestart) << "run_script \"more\" is inlined";
  EXPECT_EQ(steps[2].target_kind, TargetKind::kEverything);
  EXPECT_EQ(steps[3].action, StepAction::kWaitStatus);
  EXPECT_EQ(steps[3].target, "deep");
  EXPECT_EQ(steps[3].wait_status, "stopped");
  EXPECT_EQ(steps[4].action, StepAction::kStop);
  EXPECT_EQ(steps[4].line, 23);
}

// The error message of parsing `text`, which must fail.
std::string error_of(const std::string& text) {
  try {
    parse_config(text, "bad.pmd");
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

TEST(LauncherConfig, SyntaxErrorsNameFileAndLine) {
  EXPECT_EQ(error_of("cmd \"a\" {\n  exec = \"x\"\n}\n"),
            "bad.pmd:3: expected ';' after the value of 'exec', found '}'");
  EXPECT_EQ(error_of("\n\ncmd \"a\" { exec = \"x;\n"), "bad.pmd:3: unterminated string");
  EXPECT_EQ(error_of("group \"g\" {\n cmd \"a\" { exec = \"x\"; }\n"),
            "bad.pmd:3: expected 'cmd', 'group' or '}' in group \"g\", found end of file");
  EXPECT_EQ(error_of("cmd \"a\" { exec = \"x\"; }\n\ncmd \"a\" { exec = \"y\"; }"),
            "bad.pmd:3: command \"a\" already defined at line 1");
  EXPECT_EQ(error_of("cmd \"a\" {\n exec = \"x\";\n colour = \"red\";\n}"),
            "bad.pmd:3: unknown attribute 'colour' (known: exec, host, deputy, auto_respawn, stop_signal, "
            "stop_time_allowed)");
  EXPECT_EQ(error_of("cmd \"a\" {\n exec = \"x\";\n auto_respawn = \"yes\";\n}"),
            "bad.pmd:3: auto_respawn must be \"true\" or \"false\", got \"yes\"");
  EXPECT_EQ(error_of("cmd \"a\" { exec = \"x\"; stop_signal = 99; }"),
            "bad.pmd:1: stop_signal must be a signal number 1-64, got 99");
  EXPECT_EQ(error_of("\ncmd \"a\" { host = \"h\"; }"), "bad.pmd:2: cmd \"a\" has no exec");
  EXPECT_EQ(error_of("cmd \"a\" { exec = \"x\"; exec = \"y\"; }"), "bad.pmd:1: 'exec' given twice in cmd \"a\"");
  EXPECT_EQ(error_of("cmd \"a\" { exec = \"x\"; host = \"h\"; deputy = \"i\"; }"),
            "bad.pmd:1: 'deputy' given twice in cmd \"a\"");
  EXPECT_EQ(error_of("group \"a/b\" { }"), "bad.pmd:1: group name 'a/b' contains '/' (nest groups instead)");
  EXPECT_EQ(error_of("command \"a\" { }"), "bad.pmd:1: expected 'group', 'cmd' or 'script', found 'command'");
  EXPECT_EQ(error_of("cmd \"a\" { exec = \"x\"; } @"), "bad.pmd:1: unexpected character '@'");
  EXPECT_EQ(error_of("# @default 1X = 2\n"), "bad.pmd:1: expected '# @default NAME = VALUE'");
}

TEST(LauncherConfig, ScriptErrorsNameTheStepsLine) {
  const std::string cmd = "cmd \"a\" { exec = \"x\"; }\n";
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n start cmd \"b\";\n}"), "bad.pmd:3: no cmd \"b\"");
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n start group \"g\";\n}"), "bad.pmd:3: no group \"g\"");
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n run_script \"t\";\n}\nscript \"t\" {\n run_script \"s\";\n}"),
            "bad.pmd:6: script \"s\" runs itself");
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n wait ms;\n}"), "bad.pmd:3: expected a number of milliseconds, found ';'");
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n start cmd \"a\" wait \"done\";\n}"),
            "bad.pmd:3: status must be \"running\" or \"stopped\", got \"done\"");
  EXPECT_EQ(error_of(cmd + "script \"s\" {\n launch cmd \"a\";\n}"),
            "bad.pmd:3: unknown script action 'launch' (start, stop, restart, wait, run_script)");
}

TEST(LauncherConfig, UnreadableFileIsAConfigError) { EXPECT_THROW(load_config("/nonexistent/x.pmd"), ConfigError); }

TEST(LauncherConfig, ProcmanAttributesWithoutMeaningHereAreWarnings) {
  const Config c = parse_config("cmd \"a\" {\n exec = \"x\";\n nickname = \"a\";\n}", "old.pmd");
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_EQ(c.warnings[0], "old.pmd:3: attribute 'nickname' ignored");
}

// Every shipped configuration must parse (real procman reads the same files).
TEST(LauncherConfig, ShippedConfigurationsParse) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(IVOA_SOURCE_DIR "/procman_configs")) {
    if (entry.path().extension() != ".pmd") continue;
    SCOPED_TRACE(entry.path().string());
    const Config c = load_config(entry.path().string());
    EXPECT_FALSE(c.commands.empty());
    EXPECT_TRUE(c.warnings.empty());
    for (const auto& s : c.scripts) EXPECT_NO_THROW(flatten_script(c, s.name));
    ++n;
  }
  EXPECT_GE(n, 4) << "sim, record, deploy, replay";
}

}  // namespace
}  // namespace ivoa::launcher
