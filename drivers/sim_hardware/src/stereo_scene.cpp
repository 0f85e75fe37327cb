#include "ivoa/sim_hardware/stereo_scene.hpp"

#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ivoa/sim_hardware/frame_stamp.hpp"

namespace ivoa::sim_hardware {
namespace {

// Saturated colours (BGR) so that a red/blue swap in demosaicing shows.
const cv::Vec3b kPalette[8] = {{0, 0, 230},   {0, 200, 0},   {230, 0, 0},     {0, 220, 220},
                               {220, 220, 0}, {210, 0, 210}, {200, 200, 200}, {40, 40, 40}};

int floor_div(int64_t a, int b) { return static_cast<int>(a >= 0 ? a / b : -((-a + b - 1) / b)); }

uint32_t cell_hash(int cx, int cy) {
  uint32_t h = static_cast<uint32_t>(cx) * 73856093u ^ static_cast<uint32_t>(cy) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  return h ^ (h >> 15);
}

cv::Mat load_bgr(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) throw std::runtime_error(path + ": cannot read image file");
  return image;
}

}  // namespace

const char* rig_camera_name(RigCamera camera) { return camera == RigCamera::kLeft ? "left" : "right"; }

StereoScene::StereoScene(const PatternOptions& pattern, bool stamp) : pattern_(pattern), stamp_(stamp) {
  if (pattern_.cell_px < 6) throw std::invalid_argument("pattern cell size must be at least 6 pixels");
}

StereoScene::StereoScene(const std::vector<std::string>& left_files, const std::vector<std::string>& right_files,
                         bool stamp)
    : stamp_(stamp) {
  if (left_files.empty() || left_files.size() != right_files.size())
    throw std::invalid_argument("need the same, non-zero number of left and right image files (got " +
                                std::to_string(left_files.size()) + " and " + std::to_string(right_files.size()) + ")");
  for (const auto& f : left_files) files_[0].push_back(load_bgr(f));
  for (const auto& f : right_files) files_[1].push_back(load_bgr(f));
}

int StereoScene::texture_x(RigCamera camera, uint32_t tick) const {
  const int64_t shift = static_cast<int64_t>(tick) * pattern_.speed_px;
  const int disparity = camera == RigCamera::kRight ? pattern_.disparity_px : 0;
  // Keep the origin within int range; the pattern has no period, so wrap
  // only at a multiple of the cell size.
  const int64_t period = static_cast<int64_t>(pattern_.cell_px) * 1000003;
  return static_cast<int>(shift % period) + disparity;
}

cv::Mat StereoScene::render_pattern(RigCamera camera, uint32_t tick, cv::Size size) const {
  cv::Mat image(size, CV_8UC3);
  const int x0 = texture_x(camera, tick);
  const int cell = pattern_.cell_px;
  for (int y = 0; y < size.height; ++y) {
    auto* row = image.ptr<cv::Vec3b>(y);
    const int cy = y / cell;
    for (int x = 0; x < size.width; ++x) row[x] = kPalette[cell_hash(floor_div(x0 + x, cell), cy) % 8];
  }
  return image;
}

cv::Mat StereoScene::file_frame(RigCamera camera, uint32_t tick, cv::Size size) const {
  const int side = camera == RigCamera::kLeft ? 0 : 1;
  const size_t index = tick % files_[side].size();
  std::lock_guard<std::mutex> lock(cache_mutex_);
  auto key = std::make_tuple(side, index, size.width, size.height);
  auto it = resized_.find(key);
  if (it == resized_.end()) {
    cv::Mat resized;
    const cv::Mat& original = files_[side][index];
    if (original.size() == size) resized = original.clone();
    else cv::resize(original, resized, size, 0, 0, cv::INTER_AREA);
    it = resized_.emplace(key, resized).first;
  }
  return it->second.clone();
}

cv::Mat StereoScene::render(RigCamera camera, const FrameStamp& stamp, cv::Size size) const {
  const uint32_t tick = stamp.tick & kStampTickMask;
  cv::Mat image = is_pattern() ? render_pattern(camera, tick, size) : file_frame(camera, tick, size);
  if (stamp_) write_stamp(image, {tick, stamp.off_beat});
  return image;
}

cv::Mat StereoScene::flat_colour_mask(RigCamera camera, uint32_t tick, cv::Size size) const {
  if (!is_pattern()) return {};
  tick &= kStampTickMask;
  constexpr int kMargin = 2;
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  const int x0 = texture_x(camera, tick);
  const int cell = pattern_.cell_px;
  const int first_row = stamp_ ? kStampBlockPx + kMargin : 0;
  for (int y = first_row; y < size.height - kMargin; ++y) {
    const int in_y = y % cell;
    if (in_y < kMargin || in_y >= cell - kMargin) continue;
    auto* row = mask.ptr<uint8_t>(y);
    for (int x = kMargin; x < size.width - kMargin; ++x) {
      const int in_x = ((x0 + x) % cell + cell) % cell;
      if (in_x >= kMargin && in_x < cell - kMargin) row[x] = 255;
    }
  }
  return mask;
}

}  // namespace ivoa::sim_hardware
