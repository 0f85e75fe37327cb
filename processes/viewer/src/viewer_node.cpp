#include "ivoa/viewer/viewer_node.hpp"

#include <spdlog/spdlog.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/introspection_content.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/stereo_image_t.hpp"

namespace ivoa::viewer {

ViewerNode::ViewerNode(Bus& bus, Heartbeat& heartbeat, ViewerOptions options)
    : bus_(bus),
      heartbeat_(heartbeat),
      options_(std::move(options)),
      matcher_([&] {
        MatcherOptions m = options_.matcher;
        m.every_frame = options_.every_frame;
        return m;
      }()),
      writer_(options_.output) {
  if (writer_.earlier_figures() > 0)
    spdlog::info("{} figures an earlier run left in {} count towards --max-images {}", writer_.earlier_figures(),
                 options_.output.out_dir, options_.output.max_images);
  std::string why_not;
  if (options_.window && !window_possible(&why_not)) {
    spdlog::warn("not opening a window: {}", why_not);
    options_.window = false;
  }
  subscribe();
  heartbeat_.set_state("waiting for images");
  if (!options_.every_frame) worker_ = std::thread([this] { work(); });
}

ViewerNode::~ViewerNode() {
  frames_.close();
  if (worker_.joinable()) worker_.join();
}

void ViewerNode::subscribe() {
  bus_.subscribe<stereo_image_t>(options_.stereo_channel, [this](const stereo_image_t& msg, const ReceiveInfo&) {
    heartbeat_.count_in();
    matcher_.add_image(msg.utime, msg.left, monotonic_ms());
    if (!seen_image_) heartbeat_.set_state("drawing");
    seen_image_ = true;
  });
  bus_.subscribe<obstacle_grid_t>(options_.stereo_grid_channel,
                                  [this](const obstacle_grid_t& msg, const ReceiveInfo& info) {
                                    if (usable(info, msg.utime, grid_content_error(msg)))
                                      matcher_.add_stereo_grid(msg, monotonic_ms());
                                  });
  bus_.subscribe<obstacle_grid_t>(options_.depth_grid_channel,
                                  [this](const obstacle_grid_t& msg, const ReceiveInfo& info) {
                                    if (usable(info, msg.utime, grid_content_error(msg)))
                                      matcher_.add_depth_grid(msg, monotonic_ms());
                                  });
  bus_.subscribe<introspection_labels_t>(options_.labels_channel,
                                         [this](const introspection_labels_t& msg, const ReceiveInfo& info) {
                                           if (usable(info, msg.utime, labels_content_error(msg)))
                                             matcher_.add_labels(msg, monotonic_ms());
                                         });
  bus_.subscribe<introspection_t>(options_.introspection_channel,
                                  [this](const introspection_t& msg, const ReceiveInfo& info) {
                                    std::string problem = introspection_content_error(msg);
                                    if (problem.empty()) problem = check_introspection(msg);
                                    if (usable(info, msg.utime, problem))
                                      matcher_.add_introspection(msg, monotonic_ms());
                                  });
  bus_.on_decode_error([this](const std::string& what) { heartbeat_.bad_input(what); });
}

// Counts the message in; one whose content cannot be drawn (`problem`) is
// bad input, not drawn as if it were valid (NaN probabilities looked like
// certain free cells).
bool ViewerNode::usable(const ReceiveInfo& info, int64_t utime, const std::string& problem) {
  heartbeat_.count_in();
  if (problem.empty()) return true;
  heartbeat_.bad_input(info.channel + " utime " + std::to_string(utime) + ": " + problem);
  return false;
}

void ViewerNode::hand_out(FrameSet frame) {
  if (options_.every_frame) draw(frame);
  else frames_.put(std::move(frame));
}

void ViewerNode::tick() {
  while (auto frame = matcher_.take(monotonic_ms())) {
    hand_out(std::move(*frame));
    if (!options_.every_frame) break;
  }
  update_drop_count();
  if (!options_.window) return;
  if (auto figure = display_.take(std::chrono::milliseconds(0))) window_.show(*figure);
  if (window_.poll()) quit_ = true;
}

void ViewerNode::update_drop_count() {
  const uint64_t dropped = matcher_.skipped() + frames_.dropped();
  if (dropped > counted_dropped_) heartbeat_.count_dropped(static_cast<int64_t>(dropped - counted_dropped_));
  counted_dropped_ = dropped;
  heartbeat_.set_counter("late_parts", static_cast<int64_t>(matcher_.late()));
  heartbeat_.set_counter("clock_restarts", static_cast<int64_t>(matcher_.clock_restarts()));
}

void ViewerNode::finish() {
  while (auto frame = matcher_.take(monotonic_ms(), true)) {
    hand_out(std::move(*frame));
    if (!options_.every_frame) break;
  }
  update_drop_count();
  frames_.close();
  if (worker_.joinable()) worker_.join();
  window_.close();
}

bool ViewerNode::done() const {
  return output_failed_.load() || quit_.load() || (options_.max_figures > 0 && figures_.load() >= options_.max_figures);
}

void ViewerNode::work() {
  while (true) {
    auto frame = frames_.take(std::chrono::milliseconds(50));
    if (frame) draw(*frame);
    else if (frames_.closed()) return;
  }
}

void ViewerNode::draw(const FrameSet& frame) {
  cv::Mat left;
  try {
    left = decode_image(*frame.left);
  } catch (const std::exception& e) {  // ImageError, or OpenCV's
    heartbeat_.bad_input(options_.stereo_channel + " utime " + std::to_string(frame.utime) +
                         ": left image: " + e.what());
    return;
  }
  cv::Mat figure;
  try {
    figure = draw_frame_figure(left, frame, options_.figure);
  } catch (const std::exception& e) {  // what check_introspection did not foresee: the frame is skipped, not the run
    heartbeat_.bad_input(options_.stereo_channel + " utime " + std::to_string(frame.utime) +
                         ": cannot draw: " + e.what());
    return;
  }
  try {
    writer_.write(figure, frame.utime, monotonic_ms());
  } catch (const OutputError& e) {
    spdlog::error("{}", e.what());
    output_failed_ = true;
    return;
  }
  if (options_.window) display_.put(figure);
  heartbeat_.latency(monotonic_ms() - frame.image_received_ms);
  heartbeat_.count_out();
  heartbeat_.set_counter("images_written", writer_.images_written());
  heartbeat_.set_counter("video_frames", writer_.video_frames());
  ++figures_;
}

}  // namespace ivoa::viewer
