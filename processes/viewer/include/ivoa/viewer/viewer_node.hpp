#pragma once
// The viewer process's logic. LCM handlers (the bus thread) file each
// message under its frame's utime (FrameMatcher); tick() hands the newest
// drawable frame to a latest-value mailbox; a worker thread decodes the
// left image, draws the figure and writes it (PNG, video), so a slow disk
// skips frames (counted) instead of falling behind. The window, if any, is
// shown from tick(), on the bus thread: highgui wants a single GUI thread.
#include <atomic>
#include <string>
#include <thread>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/heartbeat.hpp"
#include "ivoa/core/mailbox.hpp"
#include "ivoa/viewer/figure.hpp"
#include "ivoa/viewer/figure_window.hpp"
#include "ivoa/viewer/figure_writer.hpp"
#include "ivoa/viewer/frame_matcher.hpp"

namespace ivoa::viewer {

struct ViewerOptions {
  std::string stereo_channel{channels::kStereoImages};
  std::string stereo_grid_channel{channels::kObstaclesStereo};
  std::string depth_grid_channel{channels::kObstaclesDepth};
  std::string labels_channel{channels::kIntrospectionLabels};
  std::string introspection_channel{channels::kIntrospection};
  MatcherOptions matcher;
  FigureOptions figure;
  OutputOptions output;
  bool window = false;       // show a window where there is a display
  int64_t max_figures = 0;   // > 0: done() after this many figures
  bool every_frame = false;  // logs: draw every frame in order, on the bus thread (reading waits)
};

class ViewerNode {
 public:
  // Throws OutputError if the outputs cannot be set up.
  ViewerNode(Bus& bus, Heartbeat& heartbeat, ViewerOptions options);
  ~ViewerNode();  // stops the worker

  // Call from the bus thread between handle() calls.
  void tick();
  // Hands out the best remaining frame and waits until the worker has drawn
  // everything handed out (end of a log, shutdown).
  void finish();

  int64_t figures() const { return figures_.load(); }
  bool done() const;  // max_figures reached, the window asked to quit, or an output failed
  bool output_failed() const { return output_failed_.load(); }
  bool window_shown() const { return window_.open(); }

 private:
  void subscribe();
  bool usable(const ReceiveInfo& info, int64_t utime, const std::string& problem);
  void work();
  void draw(const FrameSet& frame);
  void hand_out(FrameSet frame);
  void update_drop_count();

  Bus& bus_;
  Heartbeat& heartbeat_;
  ViewerOptions options_;
  FrameMatcher matcher_;  // bus thread only
  FigureWriter writer_;   // worker thread only (after construction)
  FigureWindow window_;   // bus thread only
  LatestMailbox<FrameSet> frames_;
  LatestMailbox<cv::Mat> display_;  // drawn figures for the window
  std::atomic<int64_t> figures_{0};
  std::atomic<bool> output_failed_{false}, quit_{false};
  uint64_t counted_dropped_ = 0;
  bool seen_image_ = false;
  std::thread worker_;
};

}  // namespace ivoa::viewer
