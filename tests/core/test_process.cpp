// What every executable shares: its common flags and the small file outputs
// (--json, --ready-file).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/process.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

// Parses `args` after a program name with the given common flags added.
int parse(void (*add)(CLI::App&, CommonOptions&), std::vector<const char*> args, CommonOptions& options) {
  CLI::App app;
  add(app, options);
  args.insert(args.begin(), "tool");
  return parse_command_line(app, static_cast<int>(args.size()), const_cast<char**>(args.data()));
}

TEST(CommonOptions, ProcessesTakeAnLcmUrlAndOfflineToolsRefuseOne) {
  CommonOptions process;
  EXPECT_EQ(parse(add_common_options, {"--lcm-url", "memq://", "--log-level", "warn"}, process), -1);
  EXPECT_EQ(process.lcm_url, "memq://");
  EXPECT_EQ(process.log_level, "warn");

  CommonOptions offline;
  EXPECT_EQ(parse(add_offline_options, {"--log-level", "error"}, offline), -1);
  EXPECT_EQ(offline.log_level, "error");
  EXPECT_EQ(parse(add_offline_options, {"--lcm-url", "memq://"}, offline), kExitUsage);
  EXPECT_EQ(parse(add_offline_options, {"--log-level", "loud"}, offline), kExitUsage);
}

// A tool that reads logs given as arguments: CLI11 took the URL for one of
// them ("logs: File does not exist: udpm://..."), naming no flag.
TEST(CommonOptions, AnOfflineToolNamesAnLcmUrlAsRefusedNotAsAMissingFile) {
  for (const char* url_arg : {"--lcm-url", "--lcm-url=udpm://239.255.76.67:7667"}) {
    CLI::App app;
    CommonOptions options;
    add_offline_options(app, options);
    std::vector<std::string> logs;
    app.add_option("logs", logs)->check(CLI::ExistingFile);
    std::vector<const char*> args = {"ivoa-tool", "/nonexistent.lcmlog", url_arg};
    if (std::string_view(url_arg) == "--lcm-url") args.push_back("udpm://239.255.76.67:7667");
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse_command_line(app, static_cast<int>(args.size()), const_cast<char**>(args.data())), kExitUsage);
    EXPECT_EQ(testing::internal::GetCapturedStderr(),
              "--lcm-url: ivoa-tool reads files and talks no LCM: give the logs as arguments\n");
  }
}

// A misspelt flag is named as unknown, not reported as the required option
// it did not set (CLI11 checks those first), in a subcommand too.
TEST(CommonOptions, AnUnknownFlagIsNamedBeforeAMissingRequiredOne) {
  const auto parse = [](std::vector<const char*> args) {
    CLI::App app;
    CommonOptions options;
    add_offline_options(app, options);
    std::string out;
    CLI::App* build = app.add_subcommand("build");
    build->add_option("--out", out)->required();
    app.require_subcommand(1);
    args.insert(args.begin(), "ivoa-tool");
    testing::internal::CaptureStderr();
    const int code = parse_command_line(app, static_cast<int>(args.size()), const_cast<char**>(args.data()));
    return std::make_pair(code, testing::internal::GetCapturedStderr());
  };
  auto [code, err] = parse({"build", "--oot", "data"});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("unknown arguments: --oot data (and --out is required)"), std::string::npos) << err;
  std::tie(code, err) = parse({"--bogus"});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_NE(err.find("unknown argument: --bogus (and A subcommand is required)"), std::string::npos) << err;
  std::tie(code, err) = parse({"build"});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_EQ(err.find("unknown"), std::string::npos) << err;
}

// A file or folder to read that is missing, or of the other kind, is an
// unusable input (exit 3) named with its flag; a bad flag stays exit 2.
TEST(CommonOptions, AMissingInputFileIsBadInputNotAUsageError) {
  test::TempDir dir;
  std::ofstream(dir.file("model.pt")) << "x";
  const auto parse_inputs = [](std::vector<const char*> args) {
    CLI::App app;
    CommonOptions options;
    add_offline_options(app, options);
    std::string model, dataset;
    int steps = 0;
    app.add_option("--model", model)->check(input_file());
    app.add_option("--dataset", dataset)->check(input_folder());
    app.add_option("--steps", steps)->check(positive_number());
    args.insert(args.begin(), "ivoa-tool");
    testing::internal::CaptureStderr();
    const int code = parse_command_line(app, static_cast<int>(args.size()), const_cast<char**>(args.data()));
    return std::make_pair(code, testing::internal::GetCapturedStderr());
  };
  const std::string model = dir.file("model.pt"), folder = dir.path().string(), missing = dir.file("none.pt");
  EXPECT_EQ(parse_inputs({"--model", model.c_str(), "--dataset", folder.c_str()}).first, -1);
  auto [code, err] = parse_inputs({"--model", missing.c_str()});
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_NE(err.find("--model: cannot be read: no such file or folder: " + missing), std::string::npos) << err;
  std::tie(code, err) = parse_inputs({"--model", folder.c_str()});
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_NE(err.find("is a folder, not a file"), std::string::npos) << err;
  std::tie(code, err) = parse_inputs({"--dataset", model.c_str()});
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_NE(err.find("is a file, not a folder"), std::string::npos) << err;
  EXPECT_EQ(parse_inputs({"--model", model.c_str(), "--steps", "0"}).first, kExitUsage);
}

// ivoa-eval's --out must stay out of its dataset, whether or not it exists yet.
TEST(LiesWithin, AFolderOrAnythingBelowItAsSpeltOrResolved) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("data"));
  std::filesystem::create_directories(dir.file("elsewhere"));
  std::filesystem::create_directory_symlink(dir.file("elsewhere"), dir.file("data/linked_session"));
  const std::string data = dir.file("data");
  EXPECT_TRUE(lies_within(data, data + "/"));
  EXPECT_TRUE(lies_within(dir.file("data/s1/eval"), data)) << "not there yet";
  EXPECT_TRUE(lies_within(dir.file("data/linked_session/eval"), data)) << "resolved, it leaves the folder";
  EXPECT_TRUE(lies_within(dir.file("elsewhere/../data/x"), data));
  EXPECT_FALSE(lies_within(dir.file("data_eval"), data)) << "a sibling that shares the folder's prefix";
  EXPECT_FALSE(lies_within(dir.file("data/../eval"), data));
  EXPECT_FALSE(lies_within(dir.file("data/linked_session/../eval"), data)) << "up from the link's target";
  const std::string data_via_up = dir.file("elsewhere/../data");
  EXPECT_TRUE(lies_within(dir.file("data/linked_session/eval"), data_via_up)) << "a '..' in the folder";
  EXPECT_TRUE(lies_within(dir.file("elsewhere/../data/linked_session/eval"), data_via_up)) << "and in both";
  EXPECT_FALSE(lies_within(dir.file("data/linked_session/../eval"), data_via_up));
  // A link inside the linked session: resolved, the path leaves both folders.
  std::filesystem::create_directories(dir.file("other"));
  std::filesystem::create_directory_symlink(dir.file("other"), dir.file("elsewhere/nested"));
  const std::string nested = dir.file("elsewhere/../data/linked_session/nested/eval");
  EXPECT_TRUE(lies_within(nested, data_via_up));
  EXPECT_TRUE(lies_within(nested, dir.file("elsewhere/../data/linked_session")));
}

TEST(WritesOver, TheSameFileByAnySpellingOrAFileInsideTheInputFolder) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("data/office_s1"));
  std::ofstream(dir.file("data/office_s1/samples.csv")) << "x";
  std::ofstream(dir.file("scene.yaml")) << "x";
  const std::string data = dir.file("data"), scene = dir.file("scene.yaml");
  EXPECT_TRUE(writes_over(dir.file("data/office_s1/samples.csv"), data));
  EXPECT_TRUE(writes_over(dir.file("data/../data/office_s1/samples.csv"), data + "/"));
  EXPECT_FALSE(writes_over(dir.file("data/new.csv"), data)) << "a new file writes over nothing";
  EXPECT_TRUE(writes_over(dir.file("./scene.yaml"), scene));
  EXPECT_TRUE(writes_over(dir.file("out.csv"), dir.file("./out.csv"))) << "neither exists yet";
  EXPECT_FALSE(writes_over(dir.file("data2/x.csv"), data)) << "a sibling that shares the folder's prefix";
  EXPECT_FALSE(writes_over(dir.file("causes.csv"), data));
  EXPECT_FALSE(writes_over(dir.file("causes.csv"), scene));
  EXPECT_FALSE(writes_over("", data));
  const auto here = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  EXPECT_TRUE(writes_over("c.csv", "./c.csv")) << "relative, neither exists yet";
  EXPECT_TRUE(writes_over("data/office_s1/samples.csv", "./data"));
  std::filesystem::current_path(here);
}

TEST(CommonOptions, HeartbeatsGoToProcessStatusUnlessTheFlagNamesAnotherChannel) {
  const auto add_with_status = [](CLI::App& app, CommonOptions& o) {
    add_common_options(app, o);
    add_status_channel_option(app, o.status_channel);
  };
  CommonOptions options;
  EXPECT_EQ(parse(add_with_status, {}, options), -1);
  EXPECT_EQ(options.status_channel, "PROCESS_STATUS");
  EXPECT_EQ(parse(add_with_status, {"--status-channel", "ROBOT_B_STATUS"}, options), -1);
  EXPECT_EQ(options.status_channel, "ROBOT_B_STATUS");
  CommonOptions tool;  // a tool that publishes no heartbeat refuses the flag
  EXPECT_EQ(parse(add_common_options, {"--status-channel", "ROBOT_B_STATUS"}, tool), kExitUsage);
}

// ivoa-launch hands its --status-channel to its commands this way.
TEST(CommonOptions, TheEnvironmentsStatusChannelIsTheDefaultAndTheFlagOrConfigBeatIt) {
  const auto add_with_status = [](CLI::App& app, CommonOptions& o) {
    add_common_options(app, o);
    add_status_channel_option(app, o.status_channel);
  };
  test::TempDir dir;
  const std::string config = dir.file("robot.ini");
  std::ofstream(config) << "status-channel = FROM_CONFIG\n";
  ASSERT_EQ(setenv(kStatusChannelEnv, "FROM_ENV", 1), 0);
  CommonOptions from_env, from_flag, from_config;
  EXPECT_EQ(parse(add_with_status, {}, from_env), -1);
  EXPECT_EQ(parse(add_with_status, {"--status-channel", "FROM_FLAG"}, from_flag), -1);
  EXPECT_EQ(parse(add_with_status, {"--config", config.c_str()}, from_config), -1);
  unsetenv(kStatusChannelEnv);
  EXPECT_EQ(from_env.status_channel, "FROM_ENV");
  EXPECT_EQ(from_flag.status_channel, "FROM_FLAG");
  EXPECT_EQ(from_config.status_channel, "FROM_CONFIG");
}

TEST(CommonOptions, ConfigFileSetsFlagsAndRefusesKeysThatNameNone) {
  test::TempDir dir;
  const std::string good = dir.file("good.ini"), typo = dir.file("typo.ini");
  std::ofstream(good) << "log-level = warn\n";
  std::ofstream(typo) << "log-levle = warn\n";
  CommonOptions options;
  EXPECT_EQ(parse(add_offline_options, {"--config", good.c_str()}, options), -1);
  EXPECT_EQ(options.log_level, "warn");
  testing::internal::CaptureStderr();
  EXPECT_EQ(parse(add_common_options, {"--config", typo.c_str()}, options), kExitUsage);
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "--config " + typo + ": 'log-levle' is not an option of this program (see --help)\n");
}

TEST(CommonOptions, ABadValueFromAConfigFileNamesTheFile) {
  test::TempDir dir;
  const std::string bad = dir.file("bad.ini");
  std::ofstream(bad) << "steps = many\nseed = abc\n";
  const auto parse_steps = [&](std::vector<const char*> args) {
    CLI::App app;
    CommonOptions options;
    add_offline_options(app, options);
    int steps = 1, seed = 0;
    app.add_option("-s,--steps", steps)->check(positive_number());
    app.add_option("--seed", seed);  // no check: CLI11's own conversion error
    args.insert(args.begin(), "tool");
    testing::internal::CaptureStderr();
    const int code = parse_command_line(app, static_cast<int>(args.size()), const_cast<char**>(args.data()));
    return std::pair{code, testing::internal::GetCapturedStderr()};
  };
  const auto [code, said] = parse_steps({"--config", bad.c_str()});
  EXPECT_EQ(code, kExitUsage);
  EXPECT_EQ(said, "--config " + bad + ": --steps: must be a number, not 'many'\n");
  for (const char* given : {"--steps", "-s"}) {  // the bad value is the command line's
    const auto [flag_code, flag_said] = parse_steps({"--config", bad.c_str(), given, "0", "--seed", "1"});
    EXPECT_EQ(flag_code, kExitUsage);
    EXPECT_EQ(flag_said.find("--config"), std::string::npos) << given << ": " << flag_said;
  }
  const auto [seed_code, seed_said] = parse_steps({"--config", bad.c_str(), "--steps", "2"});
  EXPECT_EQ(seed_code, kExitUsage);
  EXPECT_EQ(seed_said.rfind("--config " + bad + ": ", 0), 0u) << seed_said;
  EXPECT_NE(seed_said.find("--seed"), std::string::npos) << seed_said;
}

// What a check says of `text` ("" if it passes).
std::string verdict(const CLI::Validator& check, std::string text) { return check(text); }

TEST(FlagChecks, SayWhatANumericFlagMustBeInAFewWords) {
  EXPECT_EQ(verdict(positive_number(), "2"), "");
  EXPECT_EQ(verdict(positive_number(), "0.5"), "");
  EXPECT_EQ(verdict(positive_number(), "0"), "must be > 0 and finite, not 0");
  EXPECT_EQ(verdict(positive_number(), "-3"), "must be > 0 and finite, not -3");
  EXPECT_EQ(verdict(positive_number(), "many"), "must be a number, not 'many'");
  EXPECT_EQ(verdict(positive_number(), "nan"), "must be a number, not 'nan'");
  EXPECT_EQ(verdict(finite_number(), "-2.5"), "");
  EXPECT_EQ(verdict(finite_number(), "nan"), "must be a number, not 'nan'");
  EXPECT_EQ(verdict(finite_number(), "inf"), "must be finite, not inf");
  EXPECT_EQ(verdict(positive_number(), "inf"), "must be > 0 and finite, not inf");
  EXPECT_EQ(verdict(non_negative_number(), "0"), "");
  EXPECT_EQ(verdict(non_negative_number(), "inf"), "must be >= 0 and finite, not inf");
  EXPECT_EQ(verdict(non_negative_number(), "-0.1"), "must be >= 0 and finite, not -0.1");
  EXPECT_EQ(verdict(number_in(0.05, 4), "4"), "");
  EXPECT_EQ(verdict(number_in(0.05, 4), "nan"), "must be a number, not 'nan'");
  EXPECT_EQ(verdict(number_in(0.05, 4), "4.5"), "must be in [0.05, 4], not 4.5");
  EXPECT_EQ(verdict(number_in(0, 1e9), "inf"), "must be in [0, 1e+09], not inf");
  EXPECT_EQ(verdict(odd_positive_integer(), "1"), "");
  EXPECT_EQ(verdict(odd_positive_integer(), "5"), "");
  EXPECT_EQ(verdict(odd_positive_integer(), "4"), "must be an odd whole number >= 1, not 4");
  EXPECT_EQ(verdict(odd_positive_integer(), "2.5"), "must be an odd whole number >= 1, not 2.5");
  EXPECT_EQ(verdict(odd_positive_integer(), "-1"), "must be an odd whole number >= 1, not -1");

  CLI::App app;
  int steps = 1;
  app.add_option("--steps", steps)->check(positive_number());
  const char* zero[] = {"tool", "--steps", "0"};
  EXPECT_EQ(parse_command_line(app, 3, const_cast<char**>(zero)), kExitUsage);
  const char* five[] = {"tool", "--steps", "5"};
  EXPECT_EQ(parse_command_line(app, 3, const_cast<char**>(five)), -1);
  EXPECT_EQ(steps, 5);
}

// Seeds CLI11 wrapped ("-1") or saturated, channels LCM refuses only once running.
TEST(FlagChecks, SeedsAndChannelsAreCheckedAsTyped) {
  EXPECT_EQ(verdict(seed_number(), "0"), "");
  EXPECT_EQ(verdict(seed_number(), "999999999999999999"), "");
  EXPECT_EQ(verdict(seed_number(), "-1"), "must be a whole number 0 to 999999999999999999, not -1");
  EXPECT_NE(verdict(seed_number(), "99999999999999999999"), "");
  EXPECT_NE(verdict(seed_number(), "1e3"), "");
  EXPECT_EQ(verdict(channel_name(), "STEREO_IMAGES"), "");
  EXPECT_EQ(verdict(channel_name(), std::string(64, 'S')),
            "must be a channel name of 1 to 63 characters (LCM's limit), not 64 characters");
  EXPECT_NE(verdict(channel_name(), ""), "");
  EXPECT_EQ(verdict(channel_regex(), "STEREO_IMAGES|DEPTH_.*"), "");
  EXPECT_EQ(verdict(channel_regex(), "(").rfind("is not a channel regex (GLib's syntax): ", 0), 0u);
}

TEST(WriteTextFile, WritesTheTextOrSaysItCannot) {
  test::TempDir dir;
  EXPECT_TRUE(write_text_file(dir.file("out.json"), "{\"a\": 1}\n"));
  EXPECT_EQ(test::read_file(dir.file("out.json")), "{\"a\": 1}\n");
  EXPECT_TRUE(write_text_file("", "nothing asked, nothing written"));
  EXPECT_FALSE(write_text_file(dir.file("no_such_folder/out.json"), "x"));
  EXPECT_FALSE(write_text_file("/dev/full", "a full disk is reported, not lost in the buffer"));
}

// A write that fails (a full disk; here the temporary's name is taken by a
// folder) cut the last run's file short or emptied it.
TEST(WriteTextFile, AFailedWriteKeepsThePreviousFileWhole) {
  test::TempDir dir;
  ASSERT_TRUE(write_text_file(dir.file("out.json"), "{\"run\": 1}\n"));
  std::filesystem::create_directory(dir.file("out.json.tmp"));
  EXPECT_FALSE(write_text_file(dir.file("out.json"), "{\"run\": 2}\n"));
  EXPECT_EQ(test::read_file(dir.file("out.json")), "{\"run\": 1}\n");
}

TEST(WriteReadyFile, CreatesTheFileScriptsWaitFor) {
  test::TempDir dir;
  EXPECT_TRUE(write_ready_file(dir.file("ready")));
  EXPECT_EQ(test::read_file(dir.file("ready")), "ready\n");
  EXPECT_TRUE(write_ready_file(""));
  EXPECT_FALSE(write_ready_file(dir.file("no_such_folder/ready")));
}

}  // namespace
}  // namespace ivoa
