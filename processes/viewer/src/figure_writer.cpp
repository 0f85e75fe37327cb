#include "ivoa/viewer/figure_writer.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string_view>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>
#ifdef IVOA_VIEWER_HAS_VIDEOIO
#include <opencv2/videoio.hpp>
#endif

#include "ivoa/core/image_files.hpp"
#include "ivoa/core/process.hpp"

namespace ivoa::viewer {
struct FigureWriter::Video {
#ifdef IVOA_VIEWER_HAS_VIDEOIO
  cv::VideoWriter writer;
#endif
  cv::Size size;
};

namespace {

// A figure this writer names (frame_<utime>.png), as an earlier run wrote it.
bool is_figure_name(const std::string& name) {
  constexpr std::string_view prefix = "frame_", suffix = ".png";
  if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  const std::string_view number(name.data() + prefix.size(), name.size() - prefix.size() - suffix.size());
  const size_t digits_from = number.front() == '-' ? 1 : 0;
  return number.size() > digits_from &&
         std::all_of(number.begin() + digits_from, number.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

FigureWriter::FigureWriter(OutputOptions options) : options_(std::move(options)) {
  if (!options_.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options_.out_dir, ec);
    if (ec) throw OutputError("cannot create " + options_.out_dir + ": " + ec.message());
    if (options_.max_images > 0) adopt_earlier_figures();
  }
  if (!options_.video.empty()) {
#ifndef IVOA_VIEWER_HAS_VIDEOIO
    throw OutputError("cannot write " + options_.video + ": built without OpenCV videoio (libopencv-videoio-dev)");
#endif
    // Opened at the first figure, whose size it takes: a path that cannot
    // be written is found out now.
    if (const std::string why = why_cannot_write(options_.video); !why.empty())
      throw OutputError("cannot write the video " + options_.video + ": " + why);
    video_ = std::make_unique<Video>();
  }
}

FigureWriter::~FigureWriter() = default;

void FigureWriter::write(const cv::Mat& figure, int64_t utime, double now_ms) {
  ++figures_since_png_;
  if (!options_.out_dir.empty() && figures_since_png_ >= options_.every_frames &&
      now_ms - last_png_ms_ >= options_.every_seconds * 1000.0) {
    write_png(figure, utime);
    figures_since_png_ = 0;
    last_png_ms_ = now_ms;
  }
  if (video_) write_video(figure);
}

// The figures an earlier viewer left in the folder count towards
// --max-images, oldest first: a viewer respawned all day, or started on
// the same folder every run, still holds the folder to N figures.
void FigureWriter::adopt_earlier_figures() {
  namespace fs = std::filesystem;
  std::vector<std::pair<fs::file_time_type, std::string>> found;
  std::error_code ec;
  for (fs::directory_iterator it(options_.out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code entry_ec;
    if (!it->is_regular_file(entry_ec) || !is_figure_name(it->path().filename().string())) continue;
    const fs::file_time_type time = it->last_write_time(entry_ec);
    if (!entry_ec) found.emplace_back(time, it->path().string());
  }
  std::sort(found.begin(), found.end());
  for (auto& [time, path] : found) written_.push_back(std::move(path));
  earlier_figures_ = static_cast<int64_t>(written_.size());
  keep_newest();
}

void FigureWriter::write_png(const cv::Mat& figure, int64_t utime) {
  char name[64];
  std::snprintf(name, sizeof(name), "frame_%" PRId64 ".png", utime);
  const std::string path = (std::filesystem::path(options_.out_dir) / name).string();
  if (std::string error; !write_image_file(path, figure, error)) throw OutputError(error);
  ++images_written_;
  // A utime written again (a log played twice) is the newest now, not the
  // oldest: removing the older entry would delete the file just written.
  written_.erase(std::remove(written_.begin(), written_.end(), path), written_.end());
  written_.push_back(path);
  keep_newest();
}

void FigureWriter::keep_newest() {
  while (options_.max_images > 0 && static_cast<int>(written_.size()) > options_.max_images) {
    std::error_code ec;
    std::filesystem::remove(written_.front(), ec);
    written_.pop_front();
  }
}

void FigureWriter::write_video(const cv::Mat& figure) {
#ifdef IVOA_VIEWER_HAS_VIDEOIO
  if (!video_->writer.isOpened()) {
    video_->size = figure.size();
    if (!video_->writer.open(options_.video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), options_.video_fps,
                             video_->size))
      throw OutputError("cannot open the video " + options_.video + " for writing (MJPG)");
  }
  if (figure.size() == video_->size) {
    video_->writer.write(figure);
  } else {
    cv::Mat resized;
    cv::resize(figure, resized, video_->size, 0, 0, cv::INTER_AREA);
    video_->writer.write(resized);
  }
  ++video_frames_;
#else
  (void)figure;
#endif
}

}  // namespace ivoa::viewer
