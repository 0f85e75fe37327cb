#include "ivoa/viewer/figure_writer.hpp"

#include <algorithm>
#include <charconv>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>
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

std::string figure_name(int64_t utime) {
  char name[64];
  std::snprintf(name, sizeof(name), "frame_%" PRId64 ".png", utime);
  return name;
}

// The utime of a file named as this writer names its figures, exactly
// (frame_0012.png, as ffmpeg numbers frames, is not one of them).
std::optional<int64_t> figure_utime(const std::string& name) {
  constexpr std::string_view prefix = "frame_";
  if (name.rfind(prefix, 0) != 0) return std::nullopt;
  int64_t utime = 0;
  const char* first = name.data() + prefix.size();
  const auto [end, error] = std::from_chars(first, name.data() + name.size(), utime);
  if (error != std::errc() || figure_name(utime) != name) return std::nullopt;
  return utime;
}

}  // namespace

FigureWriter::FigureWriter(OutputOptions options) : options_(std::move(options)) {
  if (!options_.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options_.out_dir, ec);
    if (ec) throw OutputError("cannot create " + options_.out_dir + ": " + ec.message());
    take_the_folder();
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

// Two viewers on one folder would each hold it to --max-images by deleting
// the oldest figures, the other's among them, and overwrite each other's
// figures of the same frame; the second is refused. The lock goes with the
// process, so a respawned viewer takes the folder back. Where the file
// system cannot lock (a share without a lock service) the viewer runs
// unguarded rather than not at all.
void FigureWriter::take_the_folder() {
  const std::string path = (std::filesystem::path(options_.out_dir) / kLockFile).string();
  try {
    folder_lock_ = FileLock::try_take(path);
  } catch (const FileLockError& e) {
    if (!e.unsupported()) throw OutputError(e.what());
    spdlog::warn("{}; not checking for another viewer writing into {}", e.what(), options_.out_dir);
    return;
  }
  if (folder_lock_) return;
  const pid_t holder = file_lock_holder(path);
  throw OutputError(options_.out_dir + ": another viewer" +
                    (holder > 0 ? " (pid " + std::to_string(holder) + ")" : std::string()) +
                    " writes its figures here: give this one another --out-dir (the two would overwrite each "
                    "other's figures of a frame, and each would delete the other's to keep the folder to "
                    "--max-images)");
}

// The figures an earlier viewer left in the folder count towards
// --max-images, oldest first: a viewer respawned all day, or started on
// the same folder every run, still holds the folder to N figures.
void FigureWriter::adopt_earlier_figures() {
  namespace fs = std::filesystem;
  struct Found {
    fs::file_time_type time;
    int64_t utime;
    std::string path;
  };
  std::vector<Found> found;
  std::error_code ec;
  for (fs::directory_iterator it(options_.out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code entry_ec;
    // Not a link: the cap removes what it counts, and a link's target is not the viewer's.
    if (!fs::is_regular_file(it->symlink_status(entry_ec))) continue;
    const std::optional<int64_t> utime = figure_utime(it->path().filename().string());
    const fs::file_time_type time = it->last_write_time(entry_ec);
    if (utime && !entry_ec) found.push_back({time, *utime, it->path().string()});
  }
  std::sort(found.begin(), found.end(),
            [](const Found& a, const Found& b) { return std::tie(a.time, a.utime) < std::tie(b.time, b.utime); });
  for (Found& f : found) written_.push_back(std::move(f.path));
  earlier_figures_ = static_cast<int64_t>(written_.size());
  keep_newest();
}

void FigureWriter::write_png(const cv::Mat& figure, int64_t utime) {
  const std::string path = (std::filesystem::path(options_.out_dir) / figure_name(utime)).string();
  if (std::string error; !write_image_file(path, figure, error)) throw OutputError(error);
  ++images_written_;
  if (options_.max_images == 0) return;  // every figure kept: nothing to count
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
