#include <sys/stat.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "ivoa/dataset/builder.hpp"
#include "ivoa/dataset/dataset_format.hpp"
#include "ivoa/dataset/patch.hpp"
#include "test_rig.hpp"

namespace ivoa::dataset {
namespace {

cv::Mat numbered_patch(int k, int size = 100) {
  cv::Mat p(size, size, CV_8UC3);
  cv::randu(p, 0, 255);
  p.at<cv::Vec3b>(0, 0) = cv::Vec3b(static_cast<uint8_t>(k), 0, 0);
  return p;
}

SessionInfo info(const std::string& name) {
  SessionInfo i;
  i.session = name;
  i.detector = "jppc";
  i.labels_from = "rerun";
  i.logs = {"/logs/a.lcmlog"};
  i.scene = "indoor_office";
  i.seed = 7;
  i.environment = "indoor";
  i.rig_name = "sim";
  return i;
}

TEST(DatasetFormat, SessionRoundTripsPatchesIndexAndMetadata) {
  test::TempDir dir;
  std::vector<cv::Mat> patches;
  {
    SessionWriter w(dir.path().string(), info("s1"));
    const int64_t f0 = w.add_frame(1000, 1004, 50);
    const int64_t f1 = w.add_frame(2000, 2004, 40);
    for (int k = 0; k < 5; ++k) {
      SampleRecord s;
      s.frame = k < 3 ? f0 : f1;
      s.utime = k < 3 ? 1000 : 2000;
      s.label = k % 4;
      s.cell = k * 3;
      s.x = 1.5f;
      s.u = 480.5f;
      s.phenomena = 3;
      s.phenomenon = 2;
      s.surface = 1;
      patches.push_back(numbered_patch(k));
      w.add_sample(s, patches.back());
    }
  }
  EXPECT_EQ(list_sessions(dir.path().string()), std::vector<std::string>{"s1"});
  const SessionReader r((dir.path() / "s1").string());
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r.info().frames, 2);
  EXPECT_EQ(r.info().samples, 5);
  EXPECT_EQ(r.info().class_counts[0], 2);  // labels 0,1,2,3,0
  EXPECT_EQ(r.info().class_counts[3], 1);
  EXPECT_EQ(r.info().environment, "indoor");
  EXPECT_EQ(r.info().seed, 7);
  EXPECT_DOUBLE_EQ(r.info().grid.safety_radius, 0.1);
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(cv::norm(r.patch(k), patches[k], cv::NORM_INF), 0) << k;
    EXPECT_EQ(r.samples()[k].label, static_cast<int>(k % 4));
    EXPECT_EQ(r.samples()[k].cell, static_cast<int>(k * 3));
  }
  EXPECT_EQ(r.samples()[4].frame, 1);
  EXPECT_FLOAT_EQ(r.samples()[0].u, 480.5f);
  EXPECT_EQ(r.samples()[0].phenomenon, 2);
}

TEST(DatasetFormat, PatchScaleSidesAndImageSizeRoundTripAndOldSessionsLackThem) {
  test::TempDir dir;
  SessionInfo scaled = info("s1");
  scaled.patch_scale = 1.6;
  scaled.image_size = {640, 480};
  scaled.tn_kept = 0.25;
  {
    SessionWriter w(dir.path().string(), scaled);
    const int64_t f = w.add_frame(1000, 1004, 2);
    SampleRecord s;
    s.frame = f;
    s.patch_side = 252;
    w.add_sample(s, numbered_patch(0));
    s.patch_side = 0;  // not given: the fixed patch
    w.add_sample(s, numbered_patch(1));
  }
  const std::string session = (dir.path() / "s1").string();
  {
    const SessionReader r(session);
    EXPECT_DOUBLE_EQ(r.info().patch_scale, 1.6);
    EXPECT_DOUBLE_EQ(r.info().tn_kept, 0.25);
    EXPECT_EQ(r.info().image_size, cv::Size(640, 480));
    EXPECT_EQ(r.samples()[0].patch_side, 252);
    EXPECT_EQ(r.samples()[1].patch_side, r.info().patch_size);
  }
  // A session written before patch_side existed: no column, no key.
  std::ifstream in(session + "/samples.csv");
  std::string header, row, csv;
  std::getline(in, header);
  csv = header.substr(0, header.rfind(',')) + "\n";
  while (std::getline(in, row)) csv += row.substr(0, row.rfind(',')) + "\n";
  in.close();
  std::ofstream(session + "/samples.csv") << csv;
  std::string json;
  {
    std::ifstream j(session + "/session.json");
    json.assign(std::istreambuf_iterator<char>(j), {});
  }
  for (const char* name : {"  \"patch_scale\"", "  \"tn_kept\"", "  \"tn_dropped\"", "  \"image_size\""}) {
    const size_t key = json.find(name);
    ASSERT_NE(key, std::string::npos) << name;
    json.erase(key, json.find('\n', key) - key + 1);
  }
  std::ofstream(session + "/session.json") << json;
  const SessionReader old(session);
  EXPECT_EQ(old.info().patch_scale, 0.0);
  EXPECT_EQ(old.info().tn_kept, 1.0) << "sessions written before thinning kept every TN cell";
  EXPECT_EQ(old.info().tn_dropped, 0);
  EXPECT_TRUE(old.info().image_size.empty()) << "sessions written before it do not know their image size";
  EXPECT_EQ(old.samples()[0].patch_side, old.info().patch_size);
}

TEST(DatasetFormat, ANonsensePatchSizeInSessionJsonIsNamedThere) {
  test::TempDir dir;
  { SessionWriter w(dir.path().string(), info("bad")); }
  const std::string path = dir.path().string() + "/bad/session.json";
  std::string json;
  {
    std::ifstream j(path);
    json.assign(std::istreambuf_iterator<char>(j), {});
  }
  const auto refused = [&](const std::string& field, const std::string& value, const std::string& message) {
    const size_t at = json.find("  \"" + field + "\": ");  // the session's, before the grid's
    ASSERT_NE(at, std::string::npos);
    std::string edited = json;
    edited.replace(at, edited.find(',', at) - at, "  \"" + field + "\": " + value);
    std::ofstream(path) << edited;
    try {
      SessionReader reader(dir.path().string() + "/bad");
      ADD_FAILURE() << "read a session with " << field << " " << value;
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("session.json: " + message), std::string::npos) << e.what();
    }
  };
  refused("patch_size", "-5", "patch_size must be 1 to 4096, not -5");
  // 2^30: patches.bin's expected size overflowed to 0, so an empty file passed
  refused("patch_size", "1073741824", "patch_size must be 1 to 4096, not 1073741824");
  // read into memory before its size was checked: 2 GB for 4e6
  refused("evidence_size", "4000000", "evidence_size must be 0 to 4096, not 4000000");
  // [width, height]: past any camera's, or not a pair of whole pixels
  const std::string size_message = "image_size must be [width, height] in pixels ([0, 0]: not known)";
  const size_t size_at = json.find("  \"image_size\": ");
  ASSERT_NE(size_at, std::string::npos);
  json.replace(size_at, json.find(']', size_at) + 1 - size_at, "  \"image_size\": 0");
  for (const char* value : {"[100000, 100000]", "\"960x600\"", "[960, 600.5]", "[960, 0]", "[960]"})
    refused("image_size", value, size_message);
}

// yaml-cpp keeps the first of two equal keys, Python's json (the report) the
// last: the two would read different sessions, so a repeat is refused at any depth.
TEST(DatasetFormat, AKeyGivenTwiceInSessionJsonIsRefusedAtAnyDepth) {
  test::TempDir dir;
  { SessionWriter w(dir.path().string(), info("twice")); }
  const std::string path = dir.path().string() + "/twice/session.json";
  std::string json = test::read_file(path);
  const size_t grid = json.find("\"grid\": {");
  ASSERT_NE(grid, std::string::npos);
  json.insert(json.find('{', grid) + 1, "\"spacing\": 0.5, ");
  std::ofstream(path) << json;
  try {
    SessionReader reader(dir.path().string() + "/twice");
    ADD_FAILURE() << "read a session whose grid gives its spacing twice";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("session.json: key 'grid.spacing' is given twice"), std::string::npos)
        << e.what();
  }
}

TEST(DatasetFormat, TwoViewPatchesRoundTripStacked) {
  test::TempDir dir;
  SessionInfo i = info("two");
  i.views = 2;
  const cv::Mat left = numbered_patch(1);
  cv::Mat stacked;
  {
    SessionWriter w(dir.path().string(), i);
    const int64_t f = w.add_frame(1000, 1004, 1);
    SampleRecord s;
    s.frame = f;
    cv::vconcat(left, numbered_patch(2), stacked);
    EXPECT_THROW(w.add_sample(s, left), DatasetError);  // one view where two are due
    w.add_sample(s, stacked);
  }
  const SessionReader r((dir.path() / "two").string());
  EXPECT_EQ(r.info().views, 2);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r.patch(0).rows, 200);
  EXPECT_EQ(cv::norm(r.patch(0), stacked, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(r.left_patch(0), left, cv::NORM_INF), 0);
}

// The error reading session s2 of `dir` ("" if none).
std::string reading_error(const test::TempDir& dir) {
  try {
    SessionReader r((dir.path() / "s2").string());
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetFormat, APatchStoreOfTheWrongSizeIsReported) {
  test::TempDir dir;
  {
    SessionWriter w(dir.path().string(), info("s2"));
    w.add_frame(1, 1, 1);
    SampleRecord s;
    w.add_sample(s, numbered_patch(1));
    w.add_sample(s, numbered_patch(2));
  }
  const auto patches = dir.path() / "s2" / "patches.bin";
  std::filesystem::resize_file(patches, 100 * 100 * 3);
  EXPECT_NE(reading_error(dir).find("30000 bytes, 1 patches; samples.csv lists 2 (truncated"), std::string::npos)
      << reading_error(dir);
  // Bytes past the last patch: the store used to be reported as "2 patches, samples.csv lists 2".
  std::filesystem::resize_file(patches, 2 * 100 * 100 * 3 + 17);
  EXPECT_NE(reading_error(dir).find("60017 bytes, not a whole number of 30000-byte patches; samples.csv lists 2"),
            std::string::npos)
      << reading_error(dir);
}

// A named pipe in place of a session's file blocked the reader for ever.
TEST(DatasetFormat, SessionFilesThatAreNoFilesAreNamed) {
  for (const char* name : {"session.json", "samples.csv", "patches.bin", "evidence.f32"}) {
    test::TempDir dir;
    SessionInfo with_evidence = info("s2");
    with_evidence.evidence_size = 2;
    {
      SessionWriter w(dir.path().string(), with_evidence);
      w.add_frame(1, 1, 1);
      w.add_sample(SampleRecord{}, numbered_patch(1), std::vector<float>{0.5F, 0.25F});
    }
    const auto file = dir.path() / "s2" / name;
    std::filesystem::remove(file);
    ASSERT_EQ(mkfifo(file.c_str(), 0600), 0) << file;
    EXPECT_NE(reading_error(dir).find(file.string() + ": is a pipe, device or socket, not a file"), std::string::npos)
        << name << ": " << reading_error(dir);
    std::filesystem::remove(file);
    std::filesystem::create_directory(file);
    EXPECT_NE(reading_error(dir).find(file.string() + ": is a folder, not a file"), std::string::npos)
        << name << ": " << reading_error(dir);
  }
}

// Predictions name the session from session.json, the report finds it by folder.
TEST(DatasetFormat, ARenamedSessionFolderIsNamed) {
  test::TempDir dir;
  {
    SessionWriter w(dir.path().string(), info("s2"));
    w.add_frame(1, 1, 1);
    w.add_sample(SampleRecord{}, numbered_patch(1));
  }
  EXPECT_NO_THROW(SessionReader((dir.path() / "s2").string() + "/"));
  std::filesystem::rename(dir.path() / "s2", dir.path() / "renamed");
  try {
    SessionReader r((dir.path() / "renamed").string());
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("names the session 's2' but its folder is 'renamed'"), std::string::npos)
        << e.what();
  }
}

// A row cut from samples.csv together with its patch leaves the store
// consistent, but session.json would still claim the old counts.
TEST(DatasetFormat, IndexThatDisagreesWithSessionJsonIsReported) {
  test::TempDir dir;
  {
    SessionWriter w(dir.path().string(), info("cut"));
    w.add_frame(1, 1, 2);
    SampleRecord fp;
    fp.label = 2;  // FP, in kLabelNames order
    w.add_sample(SampleRecord{}, numbered_patch(0));
    w.add_sample(fp, numbered_patch(1));
  }
  const auto session = dir.path() / "cut";
  std::ifstream in(session / "samples.csv");
  const std::string header_and_first = [&] {
    std::string header, first;
    std::getline(in, header);
    std::getline(in, first);
    return header + "\n" + first + "\n";
  }();
  in.close();
  std::ofstream(session / "samples.csv") << header_and_first;
  std::filesystem::resize_file(session / "patches.bin", 100 * 100 * 3);
  try {
    SessionReader r(session.string());
    FAIL() << "read a session whose index disagrees with session.json";
  } catch (const DatasetError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("session.json says 2 samples (TP 1, TN 0, FP 1, FN 0)"), std::string::npos) << what;
    EXPECT_NE(what.find("samples.csv lists 1 samples (TP 1, TN 0, FP 0, FN 0)"), std::string::npos) << what;
  }
}

// The error reading a session of two default samples (of an image of
// `image_size`) whose samples.csv has its second row edited by hand ("" if none).
std::string reading_error_after(const test::TempDir& dir, const std::function<std::string(std::string)>& edit,
                                const cv::Size& image_size = {}) {
  {
    SessionInfo hand = info("hand");
    hand.image_size = image_size;
    SessionWriter w(dir.path().string(), hand);
    w.add_frame(1, 1, 2);
    w.add_sample(SampleRecord{}, numbered_patch(0));
    w.add_sample(SampleRecord{}, numbered_patch(1));
  }
  const auto csv = dir.path() / "hand" / "samples.csv";
  std::ifstream in(csv);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  in.close();
  std::ofstream(csv) << header << "\n" << first << "\n" << edit(second) << "\n";
  try {
    SessionReader r((dir.path() / "hand").string());
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "";
}

// Column k (0-based) of a CSV row replaced by `value`.
std::string with_column(std::string row, int k, const std::string& value) {
  size_t begin = 0;
  for (int i = 0; i < k; ++i) begin = row.find(',', begin) + 1;
  const size_t end = row.find(',', begin);
  return row.replace(begin, end == std::string::npos ? std::string::npos : end - begin, value);
}

TEST(DatasetFormat, CoordinatesThatAreNotFiniteAreNamedByLineAndColumn) {
  test::TempDir dir;
  const std::string what = reading_error_after(dir, [](std::string row) { return with_column(row, 8, "nan"); });
  EXPECT_NE(what.find("hand/samples.csv line 3: column x is nan"), std::string::npos) << what;
  test::TempDir other;
  const std::string inf = reading_error_after(other, [](std::string row) { return with_column(row, 10, "inf"); });
  EXPECT_NE(inf.find("samples.csv line 3: column u is inf"), std::string::npos) << inf;
}

TEST(DatasetFormat, AColumnThatIsNotANumberIsNamed) {
  test::TempDir dir;
  const std::string what = reading_error_after(dir, [](std::string row) { return with_column(row, 5, "FP"); });
  EXPECT_NE(what.find("samples.csv line 3: column label (6 of 16) is missing or not a number"), std::string::npos)
      << what;
}

// sscanf read "16abc" as 16, and took any sample number or frame.
TEST(DatasetFormat, TrailingJunkAWrongSampleNumberAndAFrameOutsideTheSessionAreNamed) {
  const std::pair<std::function<std::string(std::string)>, std::string> cases[] = {
      {[](std::string row) { return with_column(row, 4, "16abc"); },
       "column cell (5 of 16) is missing or not a number"},
      {[](std::string row) { return with_column(row, 0, "999"); }, "sample 999 where sample 1 is due"},
      {[](std::string row) { return with_column(row, 1, "7"); }, "frame 7, but the session has"},
      {[](std::string row) { return with_column(row, 1, "-1"); }, "frame -1, but the session has"}};
  for (const auto& [edit, expected] : cases) {
    test::TempDir dir;
    const std::string what = reading_error_after(dir, edit);
    EXPECT_NE(what.find("samples.csv line 3: " + expected), std::string::npos) << what;
  }
}

// Every labelled cell's pixel lies in the image (its patch was cut there);
// one off it is refused by the writer and, edited in by hand, by the reader.
TEST(DatasetFormat, APixelOffTheImageIsRefusedWhereTheSizeIsKnown) {
  test::TempDir dir;
  SessionInfo sized = info("sized");
  sized.image_size = cv::Size(640, 480);
  SampleRecord inside;
  inside.u = 639.5f;
  inside.v = 10;
  {
    SessionWriter w(dir.path().string(), sized);
    w.add_frame(1, 1, 2);
    w.add_sample(inside, numbered_patch(0));
    SampleRecord off = inside;
    off.u = 640;
    EXPECT_THROW(w.add_sample(off, numbered_patch(1)), DatasetError);
  }
  test::TempDir edited;
  const std::string what = reading_error_after(
      edited, [](std::string row) { return with_column(row, 11, "-3"); }, cv::Size(640, 480));
  EXPECT_NE(what.find("samples.csv line 3: pixel (u 0, v -3) lies off the 640 x 480 image"), std::string::npos) << what;
}

TEST(DatasetFormat, ARowWithMoreFieldsThanTheHeaderIsNamed) {
  test::TempDir dir;
  const std::string what = reading_error_after(dir, [](std::string row) { return row + ",7"; });
  EXPECT_NE(what.find("samples.csv line 3: 17 fields, the header has 16"), std::string::npos) << what;
}

TEST(DatasetFormat, EvidenceRoundTripsPerSampleAndOldSessionsHaveNone) {
  test::TempDir dir;
  SessionInfo with = info("ev");
  with.evidence_size = 3;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  {
    SessionWriter w(dir.path().string(), with);
    w.add_frame(1, 1, 2);
    SampleRecord s;
    w.add_sample(s, numbered_patch(0), {0.25f, 0.5f, 1.25f});
    w.add_sample(s, numbered_patch(1), {nan, 0.75f, 2.0f});
    EXPECT_THROW(w.add_sample(s, numbered_patch(2)), DatasetError) << "the session stores 3 values per sample";
    EXPECT_THROW(w.add_sample(s, numbered_patch(2), {1.0f}), DatasetError);
  }
  const SessionReader r((dir.path() / "ev").string());
  ASSERT_EQ(r.info().evidence_size, 3);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_FLOAT_EQ(r.evidence(0)[2], 1.25f);
  EXPECT_TRUE(std::isnan(r.evidence(1)[0]));
  EXPECT_FLOAT_EQ(r.evidence(1)[1], 0.75f);

  {
    SessionWriter w(dir.path().string(), info("none"));
    w.add_frame(1, 1, 1);
    EXPECT_THROW(w.add_sample(SampleRecord{}, numbered_patch(0), {1.0f}), DatasetError);
    w.add_sample(SampleRecord{}, numbered_patch(0));
  }
  const SessionReader none((dir.path() / "none").string());
  EXPECT_EQ(none.info().evidence_size, 0);
  EXPECT_EQ(none.evidence(0), nullptr);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "none" / "evidence.f32"));

  {  // an infinity is damage, not "not observed" (training blamed --lr for it)
    std::fstream f((dir.path() / "ev" / "evidence.f32").string(), std::ios::in | std::ios::out | std::ios::binary);
    const float inf = std::numeric_limits<float>::infinity();
    f.seekp(4 * sizeof(float));
    f.write(reinterpret_cast<const char*>(&inf), sizeof(inf));
  }
  try {
    SessionReader damaged((dir.path() / "ev").string());
    FAIL() << "read an infinite evidence value";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("evidence.f32: sample 1 holds an infinite value"), std::string::npos)
        << e.what();
  }
  std::filesystem::resize_file(dir.path() / "ev" / "evidence.f32", 5 * sizeof(float));
  try {
    SessionReader truncated((dir.path() / "ev").string());
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("evidence.f32"), std::string::npos) << e.what();
  }
}

// "--session .." wrote the session's files into the dataset's parent folder.
TEST(DatasetFormat, SessionNameThatIsNotAFolderOfItsOwnIsRefused) {
  test::TempDir dir;
  const std::string root = (dir.path() / "data").string();
  for (const std::string name : {"", ".", "..", "a/b", ".a.partial"}) {
    try {
      SessionWriter w(root, info(name));
      FAIL() << "accepted session name '" << name << "'";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("session name '" + name + "' must be a folder name"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "patches.bin"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "data" / "patches.bin"));
}

// A log named hall,run2.lcmlog gave a session whose name ivoa-eval wrote
// unquoted into predictions.csv; the report then refused the file.
TEST(DatasetFormat, SessionNameTheCsvFilesCannotHoldIsRefusedBeforeAnyLogIsRead) {
  test::TempDir dir;
  const BuildOptions options;
  for (const std::string name : {"hall,run2", "a\"b", "tab\there"}) {
    try {
      SessionBuilder builder(dir.file("data"), name, options);
      FAIL() << "accepted session name '" << name << "'";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("has a comma, a quote or a control character"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(check_session_name("hall_run2-b.c"));
}

// "--session dataset.json" moved the dataset's index aside and deleted it.
TEST(DatasetFormat, SessionNameOfAFileInTheDatasetIsRefusedAndTheFileKept) {
  test::TempDir dir;
  std::ofstream(dir.file("dataset.json")) << "{}";
  try {
    SessionWriter w(dir.path().string(), info("dataset.json"));
    FAIL() << "accepted the name of the dataset's index";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("dataset.json is a file, not a session folder"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(test::read_file(dir.file("dataset.json")), "{}");
}

// A folder of the session's name is replaced only if it is a session built
// before: a folder holding the input log (`--session logs` beside
// logs/run.lcmlog) was deleted with the log in it.
TEST(DatasetFormat, AFolderThatIsNotASessionIsNotReplaced) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("logs"));
  std::ofstream(dir.file("logs/run.lcmlog")) << "recording";
  const auto refused = [&](const std::string& name, const std::string& message) {
    try {
      SessionWriter w(dir.path().string(), info(name));
      ADD_FAILURE() << "accepted " << name;
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused("logs", "logs is a folder without session.json, not a dataset session, so it is not replaced");
  std::ofstream(dir.file("logs/session.json")) << "{}";
  refused("logs", "logs holds run.lcmlog, which is not a session's, so it is not replaced");
  EXPECT_EQ(test::read_file(dir.file("logs/run.lcmlog")), "recording");
  {  // a session built before is replaced
    SessionWriter w(dir.path().string(), info("s1"));
    w.close();
  }
  SessionWriter again(dir.path().string(), info("s1"));
  again.close();
  EXPECT_TRUE(std::filesystem::exists(dir.file("s1/session.json")));
}

TEST(DatasetFormat, RejectsWrongPatchesAndLabels) {
  test::TempDir dir;
  SessionWriter w(dir.path().string(), info("s3"));
  w.add_frame(1, 1, 1);
  SampleRecord s;
  EXPECT_THROW(w.add_sample(s, numbered_patch(0, 64)), DatasetError);
  s.label = 7;
  EXPECT_THROW(w.add_sample(s, numbered_patch(0)), DatasetError);
}

// Builds of several sessions may run side by side into one dataset: none
// may lose another's entry or read a half-written list.
TEST(DatasetFormat, SessionsRegisteredSideBySideAreAllListed) {
  test::TempDir dir;
  const std::string root = dir.path().string();
  std::atomic<int> errors{0};
  std::vector<std::thread> builders;
  for (int t = 0; t < 4; ++t)
    builders.emplace_back([&, t] {
      for (int k = 0; k < 25; ++k) try {
          register_session(root, "b" + std::to_string(t) + "_" + std::to_string(k), 100);
        } catch (const DatasetError&) {
          ++errors;
        }
    });
  for (auto& b : builders) b.join();
  EXPECT_EQ(errors, 0);
  EXPECT_EQ(list_sessions(root).size(), 100u);
}

TEST(DatasetFormat, SplitFileBySessionRejectsOverlap) {
  test::TempDir dir;
  std::ofstream(dir.file("ok.yaml")) << "train: [a, b]\nval: [c]\ntest: [d, e]\n";
  const auto splits = load_split(dir.file("ok.yaml"));
  EXPECT_EQ(splits.at("train"), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(splits.at("test").size(), 2u);
  std::ofstream(dir.file("bad.yaml")) << "train: [a, b]\ntest: [b]\n";
  try {
    load_split(dir.file("bad.yaml"));
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("'b'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_split(dir.file("missing.yaml")), DatasetError);
  // a repeated key: a reader keeps one of the two lists, and the other would be lost unseen
  std::ofstream(dir.file("twice.yaml")) << "test: [a]\ntest: [b]\n";
  try {
    load_split(dir.file("twice.yaml"));
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("split 'test' is given twice"), std::string::npos) << e.what();
  }
  // A path names the same session twice unseen (./b and b), or another dataset's.
  for (const char* path : {"./b", "../other/b", "..", "", ".b.partial"}) {
    std::ofstream(dir.file("path.yaml")) << "train: [a, '" << path << "']\nval: [b]\n";
    try {
      load_split(dir.file("path.yaml"));
      FAIL() << path;
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("split 'train': '" + std::string(path) + "' is not a session name"),
                std::string::npos)
          << e.what();
    }
  }
}

// What a split file names must be there: the split in the file, its sessions
// in the dataset. Both errors name the file.
TEST(DatasetFormat, SplitSessionsMustBeInTheFileAndTheDataset) {
  test::TempDir dir;
  const std::string root = dir.file("data");
  for (const char* session : {"a", "b"}) {
    std::filesystem::create_directories(root + "/" + session);
    std::ofstream(root + "/" + session + "/session.json") << "{}\n";
  }
  std::ofstream(dir.file("split.yaml")) << "train: [a]\ntest: [b, c]\n";
  EXPECT_EQ(split_sessions(dir.file("split.yaml"), "train", root), std::vector<std::string>{"a"});
  const auto error_of = [&](const std::string& split) -> std::string {
    try {
      split_sessions(dir.file("split.yaml"), split, root);
    } catch (const DatasetError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error_of("val"), dir.file("split.yaml") + ": no split 'val' (it has: test, train)");
  EXPECT_EQ(error_of("test"), dir.file("split.yaml") + ": split 'test' names session 'c', which is not in " + root);
  // ivoa-train and ivoa-eval find their sessions here: a later version's index is refused here too
  std::ofstream(root + "/dataset.json") << R"({"format": "ivoa-dataset", "version": 2, "sessions": ["a", "b"]})";
  EXPECT_NE(error_of("train").find("dataset.json: dataset version 2"), std::string::npos) << error_of("train");
}

TEST(Patch, ExtractsCentredPatchesInsideTheImageOnly) {
  cv::Mat image(600, 960, CV_8UC3);
  cv::randu(image, 0, 255);
  const cv::Mat p = extract_patch(image, 200.2, 300.7, 100);
  ASSERT_FALSE(p.empty());
  EXPECT_EQ(cv::norm(p, image(cv::Rect(150, 251, 100, 100)), cv::NORM_INF), 0);
  EXPECT_TRUE(extract_patch(image, 30, 300, 100).empty());
  EXPECT_TRUE(extract_patch(image, 500, 580, 100).empty());
}

TEST(Patch, TruthSummaryUsesThePatchCentre) {
  cv::Mat phen(600, 960, CV_8UC1, cv::Scalar(0)), surf(600, 960, CV_8UC1, cv::Scalar(1));
  // Reflection (1) over most of the centre, glare (4) in a corner of it,
  // texture-less (2) only in the outer ring, which must not count.
  phen(cv::Rect(475, 275, 50, 50)).setTo(1);
  phen(cv::Rect(475, 275, 10, 10)).setTo(5);
  phen(cv::Rect(450, 250, 10, 10)).setTo(2);
  surf(cv::Rect(475, 275, 50, 30)).setTo(2);
  const PatchTruth t = summarize_truth(phen, surf, 500, 300, 100);
  EXPECT_EQ(t.phenomena, 5);
  EXPECT_EQ(t.phenomenon, 1);
  EXPECT_EQ(t.surface, 2);
}

}  // namespace
}  // namespace ivoa::dataset
