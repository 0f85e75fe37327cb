#include "ivoa/viewer/figure_window.hpp"

#include <cstdlib>

#include <spdlog/spdlog.h>
#ifdef IVOA_VIEWER_HAS_HIGHGUI
#include <opencv2/highgui.hpp>
#endif

namespace ivoa::viewer {
namespace {
[[maybe_unused]] constexpr const char* kWindowName = "ivoa-viewer";
}

bool window_possible(std::string* why_not) {
  auto fail = [&](const char* why) {
    if (why_not) *why_not = why;
    return false;
  };
#ifndef IVOA_VIEWER_HAS_HIGHGUI
  return fail("built without OpenCV highgui (libopencv-highgui-dev)");
#else
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland)) return fail("no display ($DISPLAY is not set)");
  return true;
#endif
}

FigureWindow::~FigureWindow() { close(); }

void FigureWindow::show([[maybe_unused]] const cv::Mat& figure) {
#ifdef IVOA_VIEWER_HAS_HIGHGUI
  if (closed_by_user_) return;
  if (!open_) {
    cv::namedWindow(kWindowName, cv::WINDOW_NORMAL | cv::WINDOW_KEEPRATIO);
    cv::resizeWindow(kWindowName, figure.cols, figure.rows);
    open_ = true;
    spdlog::info("window open ({}x{}; q or Esc stops the viewer)", figure.cols, figure.rows);
  } else if (cv::getWindowProperty(kWindowName, cv::WND_PROP_VISIBLE) < 1) {
    spdlog::info("window closed; writing files only");
    open_ = false;
    closed_by_user_ = true;
    return;
  }
  cv::imshow(kWindowName, figure);
#endif
}

bool FigureWindow::poll() {
#ifdef IVOA_VIEWER_HAS_HIGHGUI
  if (open_) {
    const int key = cv::waitKey(1);
    if (key == 'q' || key == 27) quit_ = true;
  }
#endif
  return quit_;
}

void FigureWindow::close() {
#ifdef IVOA_VIEWER_HAS_HIGHGUI
  if (open_) {
    cv::destroyWindow(kWindowName);
    cv::waitKey(1);  // lets the toolkit take the window down
  }
#endif
  open_ = false;
}

}  // namespace ivoa::viewer
