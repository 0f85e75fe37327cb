#include "truth_colors.hpp"

#include <cstring>

#include <opencv2/imgproc.hpp>

#include "ivoa/sim_ground_truth_t.hpp"

namespace ivoa::sim {
namespace {

using GT = sim_ground_truth_t;

const cv::Vec3b kSurfaceColors[] = {
    {235, 206, 135},  // sky
    {120, 120, 120},  // floor
    {170, 200, 225},  // wall
    {40, 40, 40},     // baseboard
    {40, 90, 140},    // door
    {60, 150, 220},   // box
    {70, 170, 70},    // cylinder
    {150, 80, 160},   // chair / furniture
    {200, 200, 200},  // curb
    {0, 0, 140},      // pit
    {225, 225, 210},  // ceiling
};
const char* kSurfaceNames[] = {"sky",      "floor",     "wall", "baseboard", "door",   "box",
                               "cylinder", "furniture", "curb", "pit",       "ceiling"};

struct PhenomenonStyle {
  int bit;
  cv::Vec3b color;
  const char* name;
};
const PhenomenonStyle kPhenomena[] = {
    {GT::PHENOMENON_REFLECTION, {255, 80, 0}, "reflection"},
    {GT::PHENOMENON_TEXTURELESS, {0, 220, 120}, "texture-less"},
    {GT::PHENOMENON_GLARE, {0, 255, 255}, "glare"},
    {GT::PHENOMENON_DARK_STRIPE, {255, 0, 255}, "dark stripe"},
    {GT::PHENOMENON_REPETITIVE, {255, 255, 0}, "repetitive"},
    {GT::PHENOMENON_LOW_LIGHT, {0, 0, 0}, "low light"},
    {GT::PHENOMENON_SATURATED, {255, 255, 255}, "saturated"},
};

}  // namespace

cv::Mat colorize_depth(const cv::Mat& depth_mm, double max_mm) {
  cv::Mat d8, out;
  depth_mm.convertTo(d8, CV_8U, -255.0 / max_mm, 255.0);
  cv::applyColorMap(d8, out, cv::COLORMAP_JET);
  out.setTo(cv::Scalar(0, 0, 0), depth_mm == 0);
  return out;
}

cv::Mat colorize_truth(const cv::Mat& surface, const cv::Mat& phenomena) {
  cv::Mat out(surface.size(), CV_8UC3);
  for (int y = 0; y < surface.rows; ++y)
    for (int x = 0; x < surface.cols; ++x) {
      const uint8_t s = surface.at<uint8_t>(y, x), p = phenomena.at<uint8_t>(y, x);
      cv::Vec3b c = s < 11 ? kSurfaceColors[s] : cv::Vec3b(255, 0, 255);
      // Each phenomenon tints its own diagonal stripes, so several can show at once.
      int k = 0;
      for (const auto& ph : kPhenomena) {
        if ((p & ph.bit) && ((x + y) / 6) % 7 == k) c = ph.color;
        ++k;
      }
      out.at<cv::Vec3b>(y, x) = c;
    }
  return out;
}

cv::Mat truth_legend(int width) {
  cv::Mat out(48, width, CV_8UC3, cv::Scalar(30, 30, 30));
  int x = 8;
  auto item = [&](const cv::Vec3b& color, const char* name, int y) {
    const int w = 14 + static_cast<int>(std::strlen(name)) * 8 + 16;
    if (x + w > width) return;
    cv::rectangle(out, cv::Rect(x, y, 12, 12), cv::Scalar(color[0], color[1], color[2]), cv::FILLED);
    cv::putText(out, name, {x + 16, y + 11}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
    x += w;
  };
  for (int s = 0; s < 11; ++s) item(kSurfaceColors[s], kSurfaceNames[s], 6);
  x = 8;
  cv::putText(out, "stripes:", {x, 39}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  x += 70;
  for (const auto& ph : kPhenomena) item(ph.color, ph.name, 28);
  return out;
}

}  // namespace ivoa::sim
