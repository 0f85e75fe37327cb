#pragma once
// Gathers what belongs to one stereo frame (its utime): the left image, the
// stereo and depth obstacle grids, the labels and the introspection output,
// which arrive on different channels at different times, or not at all.
// take() hands out the newest frame that has every part currently being
// published ("active": seen in the last few seconds); when none has for a
// while, the best there is (most parts, then newest), so a missing process
// never stops the drawing. Older frames are dropped and counted, except
// with every_frame (logs), where frames are handed out oldest first, and
// the oldest also once more than max_frames are waiting.
#include <array>
#include <cstdint>
#include <map>
#include <optional>

#include "ivoa/image_t.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/introspection_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::viewer {

enum Part : int { kImage, kStereoGrid, kDepthGrid, kLabels, kIntrospection, kNumParts };
const char* part_name(Part part);

struct FrameSet {
  int64_t utime = 0;
  double image_received_ms = 0;  // monotonic time the image arrived
  std::optional<image_t> left;
  std::optional<obstacle_grid_t> stereo, depth;
  std::optional<introspection_labels_t> labels;
  std::optional<introspection_t> introspection;

  bool has(Part part) const;
  int part_count() const;
};

struct MatcherOptions {
  size_t max_frames = 16;    // frames kept waiting for their parts (each holds a left image)
  double active_ms = 3000;   // a part seen this recently is expected in every frame
  double settle_ms = 1000;   // nothing complete for this long: draw the best frame there is
  bool every_frame = false;  // hand out every frame with an image, in order, once it or a newer one is complete
  // Parts expected in every frame even before any has been seen: a log's
  // channels, so its first frames wait for a process that was slow to start.
  std::array<bool, kNumParts> expected{};
};

inline constexpr int64_t kClockWentBackUs = 10'000'000;

class FrameMatcher {
 public:
  explicit FrameMatcher(MatcherOptions options = {});

  // Each message joins the frame of its utime; `now_ms` is monotonic time.
  // Parts of frames older than the last one taken are ignored (too late),
  // unless more than kClockWentBackUs older: the clock went back (a log
  // played again, or one frame's time jumped ahead and back), and frames
  // are taken again from there on. A frame stamped far ahead stopped the
  // drawing for good.
  void add_image(int64_t utime, image_t left, double now_ms);
  void add_stereo_grid(const obstacle_grid_t& grid, double now_ms);
  void add_depth_grid(const obstacle_grid_t& grid, double now_ms);
  void add_labels(const introspection_labels_t& labels, double now_ms);
  void add_introspection(const introspection_t& introspection, double now_ms);

  // The frame to draw now, if any. `flush`: the best frame there is, without
  // waiting (end of a log, shutdown).
  std::optional<FrameSet> take(double now_ms, bool flush = false);

  uint64_t skipped() const { return skipped_; }  // frames with an image never taken
  uint64_t late() const { return late_; }        // parts that came after their frame was drawn
  uint64_t clock_restarts() const { return clock_restarts_; }
  size_t pending() const { return frames_.size(); }

 private:
  FrameSet* slot(int64_t utime, Part part, double now_ms);
  bool complete(const FrameSet& frame, double now_ms) const;
  FrameSet hand_out(std::map<int64_t, FrameSet>::iterator it, double now_ms);
  std::optional<FrameSet> take_oldest(double now_ms, bool flush);

  MatcherOptions options_;
  std::map<int64_t, FrameSet> frames_;
  std::array<double, kNumParts> last_seen_ms_;
  std::optional<int64_t> last_taken_utime_;
  std::optional<double> last_take_ms_;
  uint64_t skipped_ = 0, late_ = 0, clock_restarts_ = 0;
};

}  // namespace ivoa::viewer
