#pragma once
// What the simulated stereo rig shows: either a procedural pattern (coloured
// squares moving sideways, the right view shifted by a known disparity) or
// frames from image files. Deterministic for a tick, so the fake cameras and
// the tests that check the driver's output render the very same images.
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/sim_hardware/frame_stamp.hpp"

namespace ivoa::sim_hardware {

enum class RigCamera { kLeft, kRight };
const char* rig_camera_name(RigCamera camera);

struct PatternOptions {
  int disparity_px = 16;  // right(x, y) = left(x + disparity, y): a fronto-parallel plane
  int speed_px = 2;       // the texture moves this many pixels left per tick
  int cell_px = 12;       // side of the coloured squares
};

class StereoScene {
 public:
  // The procedural pattern.
  explicit StereoScene(const PatternOptions& pattern, bool stamp = true);
  // Frame `tick % n` of the image files (any format cv::imread reads), resized
  // to the requested size. Left and right lists must have the same length.
  // Throws std::runtime_error naming a file that cannot be read.
  StereoScene(const std::vector<std::string>& left_files, const std::vector<std::string>& right_files,
              bool stamp = true);

  // The 8-bit BGR image a camera sees at `stamp.tick`, with the stamp
  // written in (frame_stamp.hpp) unless stamping is off. Thread-safe.
  cv::Mat render(RigCamera camera, const FrameStamp& stamp, cv::Size size) const;

  // Pixels whose colour does not depend on demosaicing: at least 2 pixels
  // from every square's edge and below the stamp (8-bit mask, 255 = use).
  // Pattern scenes only; empty for image files.
  cv::Mat flat_colour_mask(RigCamera camera, uint32_t tick, cv::Size size) const;

  bool is_pattern() const { return files_[0].empty(); }
  bool stamped() const { return stamp_; }

 private:
  int texture_x(RigCamera camera, uint32_t tick) const;
  cv::Mat render_pattern(RigCamera camera, uint32_t tick, cv::Size size) const;
  cv::Mat file_frame(RigCamera camera, uint32_t tick, cv::Size size) const;

  PatternOptions pattern_;
  bool stamp_ = true;
  std::vector<cv::Mat> files_[2];  // loaded images, left and right
  mutable std::mutex cache_mutex_;
  mutable std::map<std::tuple<int, size_t, int, int>, cv::Mat> resized_;  // (camera, index, w, h)
};

}  // namespace ivoa::sim_hardware
