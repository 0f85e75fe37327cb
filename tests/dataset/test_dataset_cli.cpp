// `ivoa-dataset` as a user runs it. info: sessions, splits and class counts;
// a folder that is not a dataset is bad input. build: flags checked up front.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>
#include <string>

#include <gtest/gtest.h>

#include "ivoa/core/process.hpp"
#include "synthetic_sessions.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

test::CommandResult dataset_info(const std::string& args) {
  return test::run_command("timeout 60 " IVOA_DATASET_EXE " info " + args);
}

TEST(DatasetInfo, ListsSessionsWithTheirSplitDetectorClassCountsAndImageSizes) {
  test::TempDir dir;
  test::SyntheticSession s;
  s.per_class = 2;
  s.image_size = {960, 600};
  test::write_synthetic_session(dir.file("data"), "a", s);
  s.detector = "dense";
  s.image_size = {};
  test::write_synthetic_session(dir.file("data"), "b", s);
  std::ofstream(dir.file("split.yaml")) << "train: [a]\ntest: [b, gone]\n";

  const auto r = dataset_info("--dataset " + dir.file("data") + " --split " + dir.file("split.yaml"));
  ASSERT_EQ(r.exit_code, kExitOk) << r.output;
  EXPECT_TRUE(contains(r.output, "train")) << r.output;
  EXPECT_TRUE(contains(r.output, "dense")) << r.output;
  EXPECT_TRUE(contains(r.output, "total: TP 4  TN 4  FP 4  FN 4")) << r.output;
  EXPECT_TRUE(contains(r.output, "image sizes: 960x600 (1 session), not recorded (1 session)")) << r.output;
  EXPECT_TRUE(contains(r.output, "names session 'gone', which is not in")) << r.output;
  EXPECT_EQ(dataset_info(dir.file("data")).exit_code, kExitOk) << "the folder may also be given bare";
}

// One damaged session is named; the others are still listed and counted.
TEST(DatasetInfo, AnUnreadableSessionIsNamedAndTheOthersListed) {
  test::TempDir dir;
  test::SyntheticSession s;
  s.per_class = 2;
  for (const char* name : {"a", "b", "c"}) test::write_synthetic_session(dir.file("data"), name, s);
  std::ofstream(dir.file("data") + "/b/samples.csv") << "cut";
  const auto r = dataset_info(dir.file("data"));
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "UNREADABLE: " + dir.file("data") + "/b/samples.csv")) << r.output;
  EXPECT_TRUE(contains(r.output, "total: TP 4  TN 4  FP 4  FN 4 (1 of 3 sessions unreadable, not counted)"))
      << r.output;
}

TEST(DatasetInfo, FolderWithoutADatasetIsBadInput) {
  test::TempDir dir;
  const auto r = dataset_info(dir.path().string());
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_TRUE(contains(r.output, "not a dataset")) << r.output;
}

// `ivoa-dataset info` on a dataset whose index is `index`: refused as bad
// input, naming `message` (the failure says which index).
void expect_index_refused(const test::TempDir& dir, const std::string& index, const std::string& message) {
  std::ofstream(dir.file("dataset.json")) << index;
  const auto r = dataset_info(dir.path().string());
  EXPECT_EQ(r.exit_code, kExitBadInput) << index << ": " << r.output;
  EXPECT_TRUE(contains(r.output, message)) << index << ": " << r.output;
}

// An empty index gave yaml-cpp's bare "bad conversion"; a session listed
// twice was counted twice.
TEST(DatasetInfo, ABrokenIndexIsNamed) {
  test::TempDir dir;
  expect_index_refused(dir, "", "dataset.json: not a dataset index");
  expect_index_refused(dir, R"({"sessions": ["a", "b", "a"]})", "dataset.json: session 'a' is listed twice");
  // yaml-cpp would read the first, the report the last
  expect_index_refused(dir, R"({"version": 1, "version": 2, "sessions": []})",
                       "dataset.json: key 'version' is given twice");
}

// A later layout read as this one would give wrong samples, not an error.
TEST(DatasetInfo, AnIndexOfAnotherVersionOrFormatIsRefused) {
  test::TempDir dir;
  expect_index_refused(dir, R"({"format": "ivoa-dataset", "version": 2, "sessions": []})",
                       "dataset.json: dataset version 2; this build reads 1 to 1");
  expect_index_refused(dir, R"({"format": "other", "version": 1, "sessions": []})",
                       "dataset.json: format 'other', not 'ivoa-dataset'");
  // checked before the sessions list, which a later version may lay out otherwise
  expect_index_refused(dir, R"({"format": "ivoa-dataset", "version": 3, "sessions": {"a": 1}})",
                       "dataset.json: dataset version 3");
  expect_index_refused(dir, R"({"version": 99999999999, "sessions": []})", "dataset version 99999999999;");
  expect_index_refused(dir, R"({"format": null, "sessions": []})", "format 'null', not 'ivoa-dataset'");
  for (const char* version : {R"("1")", "true", "0", "1.5"})
    expect_index_refused(dir, std::string(R"({"version": )") + version + R"(, "sessions": []})",
                         "is not a version number (1, 2, ...)");
}

TEST(DatasetInfo, WithoutAFolderAsksForOneAsTheArgumentOrTheFlag) {
  const auto r = dataset_info("");
  EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
  EXPECT_TRUE(contains(r.output, "ivoa-dataset info DATASET (or --dataset DATASET)")) << r.output;
}

// `ivoa-dataset build` with `flags` on a file that a flag check must refuse
// before reading it.
test::CommandResult build_refused_before_reading(const std::string& flags) {
  test::TempDir dir;
  std::ofstream(dir.file("a.lcmlog")) << "never read";
  return test::run_command("timeout 60 " IVOA_DATASET_EXE " build --out " + dir.file("data") + " " + flags + " " +
                           dir.file("a.lcmlog"));
}

// A detector flag that cannot work is refused before any log is read, by name.
TEST(DatasetBuild, DetectorFlagOutOfRangeIsAUsageError) {
  const auto r = build_refused_before_reading("--labels jppc --rect_scale -1");
  EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
  EXPECT_TRUE(contains(r.output, "rect_scale must be in [0.05, 1]")) << r.output;
}

// A pairing tolerance near 2^63 overflowed and paired no frame (exit 0).
TEST(DatasetBuild, AnOverflowingSyncToleranceIsAUsageError) {
  const auto r = build_refused_before_reading("--labels jppc --sync-tolerance-us 9223372036854775807");
  EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
  EXPECT_TRUE(contains(r.output, "--sync-tolerance-us")) << r.output;
}

// The live detector's settings file relabels offline as it is: its keys,
// outside any section, are build's (CLI11 wanted them under [build] and
// refused the file); a bad value in it is named.
TEST(DatasetBuild, TheDetectorsConfigFileSetsBuildsFlags) {
  test::TempDir dir;
  std::ifstream shipped(IVOA_DETECTOR_INI);
  std::string text((std::istreambuf_iterator<char>(shipped)), std::istreambuf_iterator<char>());
  ASSERT_TRUE(contains(text, "\nrect_scale = 0.5\n"));
  std::ofstream(dir.file("bad.ini")) << text.replace(text.find("\nrect_scale = 0.5\n"), 18, "\nrect_scale = -1\n");
  const std::string bad_config = "--config " + dir.file("bad.ini");
  for (const std::string& flags : {"--labels jppc " + bad_config, bad_config + " --labels jppc"}) {
    const auto r = build_refused_before_reading(flags);
    EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
    EXPECT_TRUE(contains(r.output, "rect_scale must be in [0.05, 1]")) << flags << ": " << r.output;
  }
  const auto r = build_refused_before_reading("--labels jppc --config " IVOA_DETECTOR_INI);
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;  // past the flags, to the log that is not one
  EXPECT_FALSE(contains(r.output, "--config")) << r.output;
}

// A misspelt --labels is a usage error listing what it takes.
TEST(DatasetBuild, UnknownLabelSourceIsAUsageErrorListingTheChoices) {
  const auto r = build_refused_before_reading("--labels jpcc");
  EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
  EXPECT_TRUE(contains(r.output, "jpcc not in {recorded,jppc,dense}")) << r.output;
}

// A dataset folder that cannot be made is a write error (exit 4, it was 3),
// said before any log is read.
TEST(DatasetBuild, AnOutputFolderThatCannotBeWrittenIsAWriteError) {
  test::TempDir dir;
  std::ofstream(dir.file("a_file")) << "in the way";
  std::ofstream(dir.file("a.lcmlog")) << "never read";
  const auto r = test::run_command("timeout 60 " IVOA_DATASET_EXE " build --out " + dir.file("a_file/data") + " " +
                                   dir.file("a.lcmlog"));
  EXPECT_EQ(r.exit_code, kExitIoError) << r.output;
  EXPECT_TRUE(contains(r.output, "cannot write the dataset folder " + dir.file("a_file/data") + ": ")) << r.output;
  EXPECT_FALSE(contains(r.output, "never read")) << r.output;
}

// Logs are grouped into sessions by name; only split parts of one recording
// may share one. Two recordings of one name (another folder, or not split)
// were built as one session, labels paired with the other log's frames.
TEST(DatasetBuild, LogsOfOneNameMustBeOneRecording) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("other"));
  for (const char* log :
       {"s.lcmlog", "s.lcmlog.01", "other/s.lcmlog", "t.lcmlog.00", "t.lcmlog.01", "other/t.lcmlog.02"})
    std::ofstream(dir.file(log)) << "not read";
  const auto build = [&](const std::string& logs) {
    return test::run_command("cd " + dir.path().string() + " && timeout 60 " IVOA_DATASET_EXE " build --out data " +
                             logs);
  };
  const std::pair<const char*, const char*> refused[] = {
      {"s.lcmlog other/s.lcmlog", "s.lcmlog and other/s.lcmlog are both session s"},
      {"s.lcmlog t.lcmlog.00 ./s.lcmlog", "./s.lcmlog is given twice: give each log once"},
      {"t.lcmlog.00 t.lcmlog.01 other/t.lcmlog.02", "t.lcmlog.00 and other/t.lcmlog.02 are both session t"},
      {"s.lcmlog t.lcmlog.00 s.lcmlog.01", "s.lcmlog and s.lcmlog.01 are both session s"},
      {"t.lcmlog.01 t.lcmlog.00",
       "the split parts of session t are given out of order: give t.lcmlog.00 before t.lcmlog.01"}};
  for (const auto& [logs, said] : refused) {
    const auto r = build(logs);
    EXPECT_EQ(r.exit_code, kExitUsage) << logs << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, said)) << logs << "\n" << r.output;
  }
  // Split parts of one folder go together, however it is spelt (and are then read: these are no logs).
  auto r = build("t.lcmlog.00 ./t.lcmlog.01");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  EXPECT_FALSE(contains(r.output, "are both session")) << r.output;
  r = build("--session joined s.lcmlog other/s.lcmlog");  // on purpose
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;
  r = build("--session joined t.lcmlog.01 t.lcmlog.00");  // but not out of order
  EXPECT_EQ(r.exit_code, kExitUsage) << r.output;
  EXPECT_TRUE(contains(r.output, "give t.lcmlog.00 before t.lcmlog.01")) << r.output;
}

// A part left out of a split recording (a glob that missed it) is said:
// the session was built with a hole in it and nothing said so.
TEST(DatasetBuild, ASplitPartNotGivenIsSaid) {
  test::TempDir dir;
  for (const char* log : {"t.lcmlog.01", "t.lcmlog.03", "u.lcmlog.00", "u.lcmlog.01"})
    std::ofstream(dir.file(log)) << "not read";
  const auto r = test::run_command("cd " + dir.path().string() +
                                   " && timeout 60 " IVOA_DATASET_EXE
                                   " build --out data t.lcmlog.01 t.lcmlog.03 u.lcmlog.00 u.lcmlog.01");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.output;  // (no logs: read and refused after the warning)
  EXPECT_TRUE(contains(r.output, "session t: 2 split parts not given (the first: t.lcmlog.00): its frames are not in"))
      << r.output;
  EXPECT_EQ(r.output.find("not given"), r.output.rfind("not given")) << "u's parts are whole\n" << r.output;
}

}  // namespace
}  // namespace ivoa
