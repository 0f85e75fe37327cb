#include "ivoa/viewer/frame_matcher.hpp"

#include <algorithm>
#include <limits>

namespace ivoa::viewer {

const char* part_name(Part part) {
  switch (part) {
    case kImage: return "image";
    case kStereoGrid: return "stereo grid";
    case kDepthGrid: return "depth grid";
    case kLabels: return "labels";
    case kIntrospection: return "introspection";
    default: return "?";
  }
}

bool FrameSet::has(Part part) const {
  switch (part) {
    case kImage: return left.has_value();
    case kStereoGrid: return stereo.has_value();
    case kDepthGrid: return depth.has_value();
    case kLabels: return labels.has_value();
    case kIntrospection: return introspection.has_value();
    default: return false;
  }
}

int FrameSet::part_count() const {
  int n = 0;
  for (int p = 0; p < kNumParts; ++p) n += has(static_cast<Part>(p));
  return n;
}

FrameMatcher::FrameMatcher(MatcherOptions options) : options_(options) {
  last_seen_ms_.fill(-std::numeric_limits<double>::infinity());
}

FrameSet* FrameMatcher::slot(int64_t utime, Part part, double now_ms) {
  last_seen_ms_[part] = now_ms;
  // Unsigned: utimes far apart, of either sign, do not overflow.
  if (last_taken_utime_ &&
      utime<*last_taken_utime_&& static_cast<uint64_t>(*last_taken_utime_) - static_cast<uint64_t>(utime)>
          kClockWentBackUs) {
    last_taken_utime_.reset();
    ++clock_restarts_;
  }
  if (last_taken_utime_ && utime <= *last_taken_utime_) {
    ++late_;
    return nullptr;
  }
  FrameSet& frame = frames_[utime];
  frame.utime = utime;
  while (frames_.size() > options_.max_frames) {
    auto victim = frames_.begin();
    if (options_.every_frame)  // frames with an image are handed out by take_oldest, never dropped
      victim = std::find_if(frames_.begin(), frames_.end(),
                            [utime](const auto& f) { return !f.second.left && f.first != utime; });
    if (victim == frames_.end()) break;
    skipped_ += victim->second.left.has_value();
    frames_.erase(victim);
  }
  const auto it = frames_.find(utime);
  return it == frames_.end() ? nullptr : &it->second;  // an old utime may be evicted at once
}

void FrameMatcher::add_image(int64_t utime, image_t left, double now_ms) {
  if (FrameSet* f = slot(utime, kImage, now_ms)) {
    f->left = std::move(left);
    f->image_received_ms = now_ms;
  }
}
void FrameMatcher::add_stereo_grid(const obstacle_grid_t& grid, double now_ms) {
  if (FrameSet* f = slot(grid.utime, kStereoGrid, now_ms)) f->stereo = grid;
}
void FrameMatcher::add_depth_grid(const obstacle_grid_t& grid, double now_ms) {
  if (FrameSet* f = slot(grid.utime, kDepthGrid, now_ms)) f->depth = grid;
}
void FrameMatcher::add_labels(const introspection_labels_t& labels, double now_ms) {
  if (FrameSet* f = slot(labels.utime, kLabels, now_ms)) f->labels = labels;
}
void FrameMatcher::add_introspection(const introspection_t& introspection, double now_ms) {
  if (FrameSet* f = slot(introspection.utime, kIntrospection, now_ms)) f->introspection = introspection;
}

bool FrameMatcher::complete(const FrameSet& frame, double now_ms) const {
  for (int p = 0; p < kNumParts; ++p) {
    const bool active = now_ms - last_seen_ms_[p] <= options_.active_ms;
    if ((active || p == kImage || options_.expected[p]) && !frame.has(static_cast<Part>(p))) return false;
  }
  return true;
}

FrameSet FrameMatcher::hand_out(std::map<int64_t, FrameSet>::iterator it, double now_ms) {
  FrameSet out = std::move(it->second);
  for (auto older = frames_.begin(); older != it; ++older) skipped_ += older->second.left.has_value();
  frames_.erase(frames_.begin(), std::next(it));
  last_taken_utime_ = out.utime;
  last_take_ms_ = now_ms;
  return out;
}

std::optional<FrameSet> FrameMatcher::take_oldest(double now_ms, bool flush) {
  auto oldest = frames_.begin();
  while (oldest != frames_.end() && !oldest->second.left) ++oldest;
  if (oldest == frames_.end()) return std::nullopt;
  // Messages come in time order: once a newer frame is complete, this one's
  // parts have all come that ever will.
  bool ready = flush || frames_.size() > options_.max_frames || complete(oldest->second, now_ms) ||
               now_ms - oldest->second.image_received_ms >= options_.settle_ms;
  for (auto it = std::next(oldest); !ready && it != frames_.end(); ++it)
    ready = it->second.left && complete(it->second, now_ms);
  if (!ready) return std::nullopt;
  return hand_out(oldest, now_ms);
}

std::optional<FrameSet> FrameMatcher::take(double now_ms, bool flush) {
  if (options_.every_frame) return take_oldest(now_ms, flush);
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it)
    if (complete(it->second, now_ms)) return hand_out(std::prev(it.base()), now_ms);
  const bool waited = !last_take_ms_ || now_ms - *last_take_ms_ >= options_.settle_ms;
  if (!flush && !waited) return std::nullopt;
  auto best = frames_.end();
  for (auto it = frames_.begin(); it != frames_.end(); ++it) {
    const FrameSet& f = it->second;
    // A frame gets settle_ms for its parts to arrive before it is drawn incomplete.
    if (!f.left || (!flush && now_ms - f.image_received_ms < options_.settle_ms)) continue;
    if (best == frames_.end() || f.part_count() >= best->second.part_count()) best = it;
  }
  if (best == frames_.end()) return std::nullopt;
  return hand_out(best, now_ms);
}

}  // namespace ivoa::viewer
