#pragma once
// Where figures go: PNG files (--out-dir; one every N figures and/or every
// S seconds; only the newest --max-images in the folder kept) and an MJPG .avi video. The
// live window is FigureWindow (figure_window.hpp).
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "ivoa/core/file_lock.hpp"

namespace ivoa::viewer {

struct OutputOptions {
  std::string out_dir;       // "" = no PNG files
  int every_frames = 1;      // a PNG every N figures ...
  double every_seconds = 0;  // ... and at least S seconds apart
  int max_images = 100;      // keep the newest N frame_*.png in out_dir, an earlier run's too (0 = all)
  std::string video;         // "" = no video; an .avi file (MJPG)
  double video_fps = 5;
};

class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class FigureWriter {
 public:
  // In out_dir, held while the writer lives: one viewer a folder.
  static constexpr const char* kLockFile = ".ivoa-viewer.lock";

  // Throws OutputError if out_dir cannot be created, or another viewer
  // writes into it.
  explicit FigureWriter(OutputOptions options);
  ~FigureWriter();

  // Throws OutputError if a PNG or the video cannot be written.
  void write(const cv::Mat& figure, int64_t utime, double now_ms);

  int64_t images_written() const { return images_written_; }
  // frame_*.png an earlier run left in out_dir, counted towards max_images.
  int64_t earlier_figures() const { return earlier_figures_; }
  int64_t video_frames() const { return video_frames_; }

 private:
  void take_the_folder();
  void adopt_earlier_figures();
  void write_png(const cv::Mat& figure, int64_t utime);
  void keep_newest();
  void write_video(const cv::Mat& figure);

  OutputOptions options_;
  std::optional<FileLock> folder_lock_;
  std::deque<std::string> written_;
  int64_t figures_since_png_ = 0, images_written_ = 0, video_frames_ = 0, earlier_figures_ = 0;
  double last_png_ms_ = -1e18;
  struct Video;
  std::unique_ptr<Video> video_;
};

}  // namespace ivoa::viewer
