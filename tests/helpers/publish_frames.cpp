// Publishes numbered full-size stereo pairs (and optionally depth images)
// at a fixed rate, for transport and logging tests. Pixel (0,0) of the left
// image holds seq % 256 so receivers can check content as well as counts.
#include <chrono>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Publish numbered test stereo pairs and depth images"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  int count = 30, width = 960, height = 600;
  double rate_hz = 30;
  bool depth = false;
  app.add_option("--count", count)->capture_default_str();
  app.add_option("--rate", rate_hz)->capture_default_str();
  app.add_option("--width", width)->capture_default_str();
  app.add_option("--height", height)->capture_default_str();
  app.add_flag("--depth", depth, "also publish a 640x480 depth image per pair");
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("test-publish", common.log_level);

  ivoa::Bus bus(common.lcm_url);
  cv::Mat left(height, width, CV_8UC3), right(height, width, CV_8UC3);
  cv::randu(left, 0, 255);
  cv::randu(right, 0, 255);
  const cv::Mat depth_mm(480, 640, CV_16UC1, cv::Scalar(1500));
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < count; ++i) {
    const int64_t utime = ivoa::now_utime();
    left.at<cv::Vec3b>(0, 0)[0] = static_cast<uint8_t>(i % 256);
    ivoa::stereo_image_t msg;
    msg.utime = utime;
    msg.seq = i;
    msg.source = "test";
    msg.left = ivoa::encode_image(left, ivoa::image_t::PIXEL_FORMAT_BGR, utime);
    msg.right = ivoa::encode_image(right, ivoa::image_t::PIXEL_FORMAT_BGR, utime);
    if (!bus.publish(ivoa::channels::kStereoImages, msg)) spdlog::error("publish {} failed", i);
    if (depth) {
      ivoa::depth_image_t d = ivoa::encode_depth(depth_mm, 570, 570, 320, 240, utime);
      d.seq = i;
      d.source = "test";
      bus.publish(ivoa::channels::kDepthImage, d);
    }
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  spdlog::info("published {} stereo pairs", count);
  return 0;
}
