// Where figures go: PNGs every N figures / S seconds with only the newest
// kept, and an MJPG .avi video.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "ivoa/viewer/figure_writer.hpp"
#include "test_rig.hpp"

namespace ivoa::viewer {
namespace {

namespace fs = std::filesystem;

cv::Mat figure() { return cv::Mat(60, 90, CV_8UC3, cv::Scalar(10, 200, 30)); }

// Every file but the writer's lock.
std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != FigureWriter::kLockFile) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// The sorted names of both lists.
std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  std::sort(a.begin(), a.end());
  return a;
}

TEST(ViewerFigureWriter, WritesEveryNthFigureAndKeepsTheNewest) {
  ivoa::test::TempDir dir;
  OutputOptions o;
  o.out_dir = dir.file("figures");
  o.every_frames = 2;
  o.max_images = 2;
  FigureWriter w(o);
  for (int64_t t = 1; t <= 6; ++t) w.write(figure(), t * 100, static_cast<double>(t));
  EXPECT_EQ(w.images_written(), 3);
  EXPECT_EQ(files_in(o.out_dir), (std::vector<std::string>{"frame_400.png", "frame_600.png"}));
}

TEST(ViewerFigureWriter, AnEarlierRunsFiguresCountTowardsTheNewestKept) {
  ivoa::test::TempDir dir;
  OutputOptions o;
  o.out_dir = dir.path().string();
  o.max_images = 3;
  // A respawned viewer: the first run's figures stay in the folder, oldest
  // first by time written; a file the viewer does not name is not its own.
  // Nor one another tool names alike (ffmpeg's frame_%04d.png), nor a link.
  for (const char* theirs : {"notes.txt", "frame_12.png.bak", "frame_0012.png", "frame_-0.png", "frame_.png"})
    std::ofstream(dir.file(theirs)) << "mine";
  fs::create_symlink(dir.file("notes.txt"), dir.file("frame_99.png"));
  const std::vector<std::string> theirs = {"frame_-0.png",     "frame_.png",   "frame_0012.png",
                                           "frame_12.png.bak", "frame_99.png", "notes.txt"};
  {
    FigureWriter first(o);
    for (int64_t t = 1; t <= 3; ++t) first.write(figure(), t, 0.0);
    EXPECT_EQ(first.earlier_figures(), 0);
  }
  fs::last_write_time(dir.file("frame_1.png"), fs::file_time_type::clock::now() - std::chrono::hours(3));
  fs::last_write_time(dir.file("frame_3.png"), fs::file_time_type::clock::now() - std::chrono::hours(2));
  fs::last_write_time(dir.file("frame_2.png"), fs::file_time_type::clock::now() - std::chrono::hours(1));
  FigureWriter second(o);
  EXPECT_EQ(second.earlier_figures(), 3);
  second.write(figure(), 7, 0.0);
  EXPECT_EQ(files_in(o.out_dir), with(theirs, {"frame_2.png", "frame_3.png", "frame_7.png"}));
  // The same utime written again (a log played twice) is the newest now:
  // the cap removes the older figures, not the file just written.
  second.write(figure(), 3, 0.0);
  second.write(figure(), 8, 0.0);
  EXPECT_EQ(files_in(o.out_dir), with(theirs, {"frame_3.png", "frame_7.png", "frame_8.png"}));
}

TEST(ViewerFigureWriter, WritesAtMostOnePngPerPeriod) {
  ivoa::test::TempDir dir;
  OutputOptions o;
  o.out_dir = dir.path().string();
  o.every_seconds = 1.0;
  o.max_images = 0;
  FigureWriter w(o);
  w.write(figure(), 1, 0.0);
  w.write(figure(), 2, 500.0);
  w.write(figure(), 3, 1000.0);
  w.write(figure(), 4, 1200.0);
  EXPECT_EQ(files_in(o.out_dir), (std::vector<std::string>{"frame_1.png", "frame_3.png"}));
}

TEST(ViewerFigureWriter, WritesAnMjpgVideo) {
  ivoa::test::TempDir dir;
  OutputOptions o;
  o.video = dir.file("view.avi");
  {
    FigureWriter w(o);
    for (int64_t t = 0; t < 5; ++t) w.write(figure(), t, 0.0);
    cv::Mat bigger(120, 180, CV_8UC3, cv::Scalar(0, 0, 0));
    w.write(bigger, 5, 0.0);  // resized to the video's size
    EXPECT_EQ(w.video_frames(), 6);
  }
  std::ifstream in(o.video, std::ios::binary);
  std::string header(12, '\0');
  in.read(header.data(), 12);
  EXPECT_EQ(header.substr(0, 4), "RIFF");
  EXPECT_EQ(header.substr(8, 4), "AVI ");
  EXPECT_GT(fs::file_size(o.video), 1000u);
}

// Each would hold the folder to --max-images by deleting the oldest
// figures, the other's too: the second viewer is refused, naming the first;
// once the first is gone (stopped, or killed and respawned) the folder is free.
TEST(ViewerFigureWriter, ASecondViewerOnTheSameFolderIsRefused) {
  ivoa::test::TempDir dir;
  OutputOptions o;
  o.out_dir = dir.file("figures");
  {
    FigureWriter first(o);
    try {
      FigureWriter second(o);
      FAIL() << "two writers on one folder";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find(o.out_dir + ": another viewer (pid " + std::to_string(::getpid()) +
                                           ") writes its figures here: give this one another --out-dir"),
                std::string::npos)
          << e.what();
    }
    first.write(figure(), 1, 0.0);
  }
  FigureWriter next(o);
  next.write(figure(), 2, 0.0);
  EXPECT_EQ(files_in(o.out_dir), (std::vector<std::string>{"frame_1.png", "frame_2.png"}));
}

TEST(ViewerFigureWriter, UnwritableOutputIsAnError) {
  ivoa::test::TempDir dir;
  std::ofstream(dir.file("a_file")) << "x";
  OutputOptions o;
  o.out_dir = dir.file("a_file") + "/figures";
  EXPECT_THROW(FigureWriter{o}, OutputError);
}

}  // namespace
}  // namespace ivoa::viewer
