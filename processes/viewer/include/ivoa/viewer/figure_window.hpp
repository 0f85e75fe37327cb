#pragma once
// The live window (OpenCV highgui), opened only where a display is. GUI
// toolkits (highgui is Qt-based on Debian) want every call from one thread:
// the viewer makes them all from its main thread.
#include <string>

#include <opencv2/core.hpp>

namespace ivoa::viewer {

// True if a window can be opened: built with highgui and $DISPLAY or
// $WAYLAND_DISPLAY set. `why_not` says why when it cannot.
bool window_possible(std::string* why_not = nullptr);

class FigureWindow {
 public:
  FigureWindow() = default;
  ~FigureWindow();
  FigureWindow(const FigureWindow&) = delete;
  FigureWindow& operator=(const FigureWindow&) = delete;

  // Opens the window at the first figure; a window the user closed stays closed.
  void show(const cv::Mat& figure);
  // Handles window events; true once 'q' or Esc was pressed in it.
  bool poll();
  void close();
  bool open() const { return open_; }

 private:
  bool open_ = false, closed_by_user_ = false, quit_ = false;
};

}  // namespace ivoa::viewer
