// ${VAR} expansion (precedence, nesting, errors with file:line), command
// selection by host, group and skip, and the "exec" form of shell commands.
#include <gtest/gtest.h>

#include "child_process.hpp"
#include "ivoa/launcher/selection.hpp"
#include "ivoa/launcher/variables.hpp"

namespace ivoa::launcher {
namespace {

EnvironmentLookup fake_environment(std::map<std::string, std::string> values) {
  return [values](const std::string& name) -> std::optional<std::string> {
    const auto it = values.find(name);
    if (it == values.end()) return std::nullopt;
    return it->second;
  };
}

const char* kConfig = R"(# @default SEED = 1
# @default SCENE = ${IVOA_CONFIG_DIR}/scenes/${SCENE_NAME}.yaml
# @default SCENE_NAME = office
# @default LOG_DIR = logs
group "sim" {
    cmd "driver" { exec = "${IVOA_BIN}/sim --seed ${SEED} --scene ${SCENE}"; }
    group "perception" {
        cmd "detector" { exec = "${IVOA_BIN}/det"; auto_respawn = "true"; }
    }
}
group "robot" {
    cmd "camera" { exec = "cam"; host = "robot1"; }
    cmd "kinect" { exec = "kin"; deputy = "robot2"; }
}
cmd "viewer" { exec = "view --model ${MODEL}"; }
)";

Variables make_variables(const Config& c, std::map<std::string, std::string> sets = {},
                         std::map<std::string, std::string> env = {}) {
  return Variables(c, std::move(sets), {{"IVOA_BIN", "/opt/bin"}, {"IVOA_CONFIG_DIR", "/cfg"}},
                   fake_environment(std::move(env)));
}

TEST(LauncherVariables, SetBeatsEnvironmentBeatsDefaultBeatsBuiltin) {
  const Config c = parse_config(kConfig, "v.pmd");
  EXPECT_EQ(make_variables(c).expand("${SEED}", "w"), "1");
  EXPECT_EQ(make_variables(c, {}, {{"SEED", "2"}}).expand("${SEED}", "w"), "2");
  EXPECT_EQ(make_variables(c, {{"SEED", "3"}}, {{"SEED", "2"}}).expand("${SEED}", "w"), "3");
  EXPECT_EQ(make_variables(c).expand("${IVOA_BIN}", "w"), "/opt/bin");
  EXPECT_EQ(make_variables(c, {}, {{"IVOA_BIN", "/usr/bin"}}).expand("${IVOA_BIN}", "w"), "/usr/bin");
}

TEST(LauncherVariables, DefaultsMayUseOtherVariables) {
  const Config c = parse_config(kConfig, "v.pmd");
  EXPECT_EQ(make_variables(c).expand("${SCENE}", "w"), "/cfg/scenes/office.yaml");
  EXPECT_EQ(make_variables(c, {{"SCENE_NAME", "lab"}}).expand("${SCENE}", "w"), "/cfg/scenes/lab.yaml");
  // Environment values are taken as they are.
  EXPECT_EQ(make_variables(c, {}, {{"SCENE", "${X}"}}).expand("${SCENE}", "w"), "${X}");
}

TEST(LauncherVariables, ShellVariablesAreLeftToTheShell) {
  const Config c = parse_config(kConfig, "v.pmd");
  EXPECT_EQ(make_variables(c).expand("echo $SEED $$ $(date) ${SEED}", "w"), "echo $SEED $$ $(date) 1");
}

TEST(LauncherVariables, UnsetCyclicAndMalformedVariablesAreErrors) {
  const Config c = parse_config("# @default A = ${B}\n# @default B = ${A}\ncmd \"x\" { exec = \"x\"; }", "v.pmd");
  const Variables v = make_variables(c);
  EXPECT_THROW(v.expand("${A}", "v.pmd:3"), ConfigError);
  try {
    v.expand("run ${NOPE}", "v.pmd:3: cmd \"x\"");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "v.pmd:3: cmd \"x\": variable ${NOPE} is not set (use --set NOPE=VALUE, export it, or add "
                 "'# @default NOPE = VALUE' to the file)");
  }
  EXPECT_THROW(v.expand("${unclosed", "w"), ConfigError);
  EXPECT_THROW(v.expand("${1A}", "w"), ConfigError);
}

// Defaults that double each other would fill the memory before the depth
// limit is reached.
TEST(LauncherVariables, AnExpansionThatExplodesIsAnError) {
  std::string text;
  for (char c = 'A'; c < 'M'; ++c)  // 3^12 copies of ten bytes: 5 MB
    text += std::string("# @default ") + c + " = ${" + char(c + 1) + "}${" + char(c + 1) + "}${" + char(c + 1) + "}\n";
  text += "# @default M = 0123456789\ncmd \"x\" { exec = \"x ${A}\"; }\n";
  const Config c = parse_config(text, "v.pmd");
  try {
    make_variables(c).expand("${A}", "v.pmd:14");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("expands to more than 1 MB"), std::string::npos) << e.what();
  }
}

TEST(LauncherVariables, KnowsTheVariablesAConfigurationUses) {
  const Config c = parse_config(kConfig, "v.pmd");
  const std::set<std::string> expected = {"IVOA_BIN", "IVOA_CONFIG_DIR", "LOG_DIR", "MODEL",
                                          "SCENE",    "SCENE_NAME",      "SEED"};
  EXPECT_EQ(variables_of(c), expected);
}

TEST(LauncherVariables, ExportedValuesAreResolvedAndSkipTheUnchangedEnvironment) {
  const Config c = parse_config(kConfig, "v.pmd");
  const auto exported = make_variables(c, {{"SEED", "5"}}, {{"LOG_DIR", "logs"}}).exported();
  EXPECT_EQ(exported.at("SEED"), "5");
  EXPECT_EQ(exported.at("SCENE"), "/cfg/scenes/office.yaml");
  EXPECT_EQ(exported.at("IVOA_BIN"), "/opt/bin");
  EXPECT_EQ(exported.count("LOG_DIR"), 0u) << "already in the environment with that value";
}

TEST(LauncherVariables, ParsesAssignments) {
  EXPECT_EQ(parse_assignment("A=b=c"), (std::pair<std::string, std::string>{"A", "b=c"}));
  EXPECT_EQ(parse_assignment("A="), (std::pair<std::string, std::string>{"A", ""}));
  EXPECT_THROW(parse_assignment("A"), std::invalid_argument);
  EXPECT_THROW(parse_assignment("-x=1"), std::invalid_argument);
}

std::vector<std::string> names(const SelectedCommands& s) {
  std::vector<std::string> out;
  for (const auto& c : s.commands) out.push_back(c.spec.name);
  return out;
}

TEST(LauncherSelection, RunsOnlyTheCommandsForTheHost) {
  const Config c = parse_config(kConfig, "v.pmd");
  const Variables v = make_variables(c, {{"MODEL", "m.pt"}});
  Selection s;
  const auto local = select_commands(c, s, v);
  EXPECT_EQ(names(local), (std::vector<std::string>{"driver", "detector", "viewer"}));
  EXPECT_EQ(local.other_hosts, (std::vector<std::string>{"camera (robot1)", "kinect (robot2)"}));
  EXPECT_EQ(local.commands[0].shell_command, "/opt/bin/sim --seed 1 --scene /cfg/scenes/office.yaml");
  s.host = "robot2";
  EXPECT_EQ(names(select_commands(c, s, v)), (std::vector<std::string>{"kinect"}));
  s.host = kAnyHost;
  EXPECT_EQ(select_commands(c, s, v).commands.size(), 5u);
}

TEST(LauncherSelection, GroupsAndSkips) {
  const Config c = parse_config(kConfig, "v.pmd");
  const Variables v = make_variables(c);  // MODEL unset: fine while the viewer is not selected
  Selection s;
  s.groups = {"sim"};
  EXPECT_EQ(names(select_commands(c, s, v)), (std::vector<std::string>{"driver", "detector"}));
  s.groups = {"sim/perception"};
  EXPECT_EQ(names(select_commands(c, s, v)), (std::vector<std::string>{"detector"}));
  s.groups = {"sim"};
  s.skip = {"sim/perception"};
  EXPECT_EQ(names(select_commands(c, s, v)), (std::vector<std::string>{"driver"}));
  s.groups = {};
  s.skip = {"viewer"};
  EXPECT_EQ(names(select_commands(c, s, v)), (std::vector<std::string>{"driver", "detector"}));
}

TEST(LauncherSelection, UnknownNamesAndUnsetVariablesAreErrors) {
  const Config c = parse_config(kConfig, "v.pmd");
  const Variables v = make_variables(c);
  Selection s;
  try {
    select_commands(c, s, v);
    FAIL() << "MODEL is not set";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("v.pmd:15: cmd \"viewer\": variable ${MODEL} is not set", 0), 0u) << e.what();
  }
  s.groups = {"nope"};
  EXPECT_THROW(select_commands(c, s, v), ConfigError);
  s.groups = {};
  s.skip = {"nope"};
  EXPECT_THROW(select_commands(c, s, v), ConfigError);
}

TEST(LauncherExecForm, SimpleCommandsReplaceTheShell) {
  EXPECT_EQ(exec_form("sleep 10"), "exec sleep 10");
  EXPECT_EQ(exec_form("  A=1 B='x y' prog --flag"), "  A=1 B='x y' exec prog --flag");
  EXPECT_EQ(exec_form("exec prog"), "exec prog");
  EXPECT_EQ(exec_form("a && b"), "a && b");
  EXPECT_EQ(exec_form("a | b"), "a | b");
  EXPECT_EQ(exec_form("trap '' INT; sleep 5"), "trap '' INT; sleep 5");
  EXPECT_EQ(exec_form("prog > out.txt"), "prog > out.txt");
  EXPECT_EQ(exec_form("echo $(date)"), "echo $(date)");
  EXPECT_EQ(exec_form("A=1"), "A=1");
  EXPECT_EQ(exec_form("exit 3"), "exit 3");
  EXPECT_EQ(exec_form("cd /tmp"), "cd /tmp");
}

}  // namespace
}  // namespace ivoa::launcher

namespace ivoa::launcher {
namespace {

// Every shipped configuration's commands expand once the robot-specific
// variables (cameras, rig, log to replay) are given.
TEST(LauncherSelection, ShippedConfigurationsExpandForEveryHost) {
  for (const char* name : {"sim", "record", "deploy", "replay"}) {
    SCOPED_TRACE(name);
    const Config c = load_config(std::string(IVOA_SOURCE_DIR "/procman_configs/") + name + ".pmd");
    const Variables v(
        c, {{"LEFT_CAMERA", "10.0.0.1"}, {"RIGHT_CAMERA", "10.0.0.2"}, {"RIG", "rig.yaml"}, {"LOG", "a.lcmlog"}},
        {{"IVOA_BIN", "/b"}, {"IVOA_CONFIG_DIR", "/c"}}, fake_environment({}));
    Selection all;
    all.host = kAnyHost;
    const auto selected = select_commands(c, all, v);
    ASSERT_EQ(selected.commands.size(), c.commands.size());
    for (const auto& cmd : selected.commands) {
      EXPECT_EQ(cmd.shell_command.find("${"), std::string::npos) << cmd.shell_command;
      EXPECT_TRUE(cmd.shell_command.rfind("/b/ivoa-", 0) == 0 || cmd.shell_command.rfind("lcm-logplayer", 0) == 0)
          << cmd.shell_command;
    }
  }
}

}  // namespace
}  // namespace ivoa::launcher
