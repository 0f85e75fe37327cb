#include "ivoa/monitor/depth_monitor.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/image_convert.hpp"

namespace ivoa::monitor {
namespace {

// Horizontal bins of side `size` over the grid region, so each cell looks
// only at points in the 3x3 bins around it.
class PointBins {
 public:
  PointBins(double x0, double y0, double size, int nx, int ny)
      : x0_(x0), y0_(y0), size_(size), nx_(nx), ny_(ny), bins_(static_cast<size_t>(nx * ny)) {}

  void add(const pcl::PointXYZ& p) {
    const int bx = bin(p.x, x0_), by = bin(p.y, y0_);
    if (bx >= 0 && bx < nx_ && by >= 0 && by < ny_) bins_[static_cast<size_t>(bx * ny_ + by)].push_back(p);
  }

  template <class Visit>
  void for_each_near(double x, double y, Visit visit) const {
    const int cx = bin(x, x0_), cy = bin(y, y0_);
    for (int bx = std::max(cx - 1, 0); bx <= std::min(cx + 1, nx_ - 1); ++bx)
      for (int by = std::max(cy - 1, 0); by <= std::min(cy + 1, ny_ - 1); ++by)
        for (const auto& p : bins_[static_cast<size_t>(bx * ny_ + by)]) visit(p);
  }

 private:
  int bin(double v, double origin) const { return static_cast<int>(std::floor((v - origin) / size_)); }
  double x0_, y0_, size_;
  int nx_, ny_;
  std::vector<std::vector<pcl::PointXYZ>> bins_;
};

// Offsets (in units of r) of the ground samples: a 5x5 lattice clipped to the disc.
constexpr std::array<std::array<double, 2>, 13> kSampleOffsets = {{{0, 0},
                                                                   {0.5, 0},
                                                                   {-0.5, 0},
                                                                   {0, 0.5},
                                                                   {0, -0.5},
                                                                   {1, 0},
                                                                   {-1, 0},
                                                                   {0, 1},
                                                                   {0, -1},
                                                                   {0.5, 0.5},
                                                                   {0.5, -0.5},
                                                                   {-0.5, 0.5},
                                                                   {-0.5, -0.5}}};

enum class SampleView { kSeen, kHidden, kHole, kNoReading };

}  // namespace

struct DepthMonitor::Impl {
  DepthMonitorConfig config;
  CameraModel camera;
  cv::Size size;
  double min_range, max_range;
  Eigen::Vector3f origin;
  // Per depth pixel, the robot-frame offset of a point at planar depth 1 m:
  // p = origin + depth * direction (lens distortion already undone).
  std::vector<Eigen::Vector3f> directions;

  explicit Impl(const RigCalibration& rig) : camera(rig.depth, rig.depth_to_robot) {}
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_near(const cv::Mat& depth_mm, const QueryGrid& grid) const;
  void count_points(const PointBins& bins, const QueryCell& cell, double r, CellEvidence& e) const;
  SampleView look_at(const cv::Mat& depth_mm, const Eigen::Vector3d& ground_point) const;
  int8_t verdict(const CellEvidence& e) const;
};

DepthMonitor::DepthMonitor(const RigCalibration& rig, DepthMonitorConfig config) : impl_(std::make_unique<Impl>(rig)) {
  Impl& m = *impl_;
  m.config = config;
  m.size = cv::Size(rig.depth.width, rig.depth.height);
  m.min_range = rig.depth_min_range;
  m.max_range = rig.depth_max_range;
  const CameraModel& camera = m.camera;
  m.origin = camera.origin().cast<float>();
  m.directions.resize(static_cast<size_t>(m.size.area()));
  for (int v = 0; v < m.size.height; ++v)
    for (int u = 0; u < m.size.width; ++u)
      m.directions[static_cast<size_t>(v * m.size.width + u)] =
          (camera.unproject({u, v}, 1.0) - camera.origin()).cast<float>();
}

DepthMonitor::~DepthMonitor() = default;
DepthMonitor::DepthMonitor(DepthMonitor&&) noexcept = default;
DepthMonitor& DepthMonitor::operator=(DepthMonitor&&) noexcept = default;

const DepthMonitorConfig& DepthMonitor::config() const { return impl_->config; }

pcl::PointCloud<pcl::PointXYZ>::Ptr DepthMonitor::Impl::cloud_near(const cv::Mat& depth_mm,
                                                                   const QueryGrid& grid) const {
  const QueryGridConfig& g = grid.config();
  const double r = g.safety_radius;
  const float x_lo = static_cast<float>(g.x_min - r),
              x_hi = static_cast<float>(g.x_min + (grid.num_x() - 1) * g.spacing + r);
  const float y_lo = static_cast<float>(g.y_min - r),
              y_hi = static_cast<float>(g.y_min + (grid.num_y() - 1) * g.spacing + r);
  const float z_lo = -1.0f, z_hi = static_cast<float>(config.obstacle_max_height);
  const uint16_t lo_mm = static_cast<uint16_t>(std::ceil(min_range * 1000.0));
  const uint16_t hi_mm = static_cast<uint16_t>(std::floor(std::min(max_range * 1000.0, 65535.0)));

  auto raw = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  raw->reserve(static_cast<size_t>(size.area() / (config.pixel_step * config.pixel_step)));
  for (int v = 0; v < size.height; v += config.pixel_step) {
    const auto* row = depth_mm.ptr<uint16_t>(v);
    for (int u = 0; u < size.width; u += config.pixel_step) {
      const uint16_t d = row[u];
      if (d < lo_mm || d > hi_mm) continue;  // 0 = no reading; outside the sensor's trusted range
      const Eigen::Vector3f p = origin + (d * 0.001f) * directions[static_cast<size_t>(v * size.width + u)];
      // Only the region the grid can ask about.
      if (p.x() < x_lo || p.x() > x_hi || p.y() < y_lo || p.y() > y_hi || p.z() < z_lo || p.z() > z_hi) continue;
      raw->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
  }
  auto filtered = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl::VoxelGrid<pcl::PointXYZ> voxel;
  const float leaf = static_cast<float>(config.voxel_size);
  voxel.setLeafSize(leaf, leaf, leaf);
  voxel.setInputCloud(raw);
  voxel.filter(*filtered);
  return filtered;
}

void DepthMonitor::Impl::count_points(const PointBins& bins, const QueryCell& cell, double r, CellEvidence& e) const {
  bins.for_each_near(cell.x, cell.y, [&](const pcl::PointXYZ& p) {
    const bool high = p.z > config.obstacle_min_height, low = p.z < -config.hole_min_depth;
    if (!high && !low) return;
    const double distance = std::hypot(p.x - cell.x, p.y - cell.y);
    const double range = (Eigen::Vector3f(p.x, p.y, p.z) - origin).norm();
    const double band = 0.5 * config.voxel_size + 3.0 * config.depth_noise_coefficient * range * range;
    if (distance <= r - band) {
      (high ? e.obstacle_points : e.hole_points)++;
    } else if (distance <= r + band) {
      (high ? e.edge_obstacle_points : e.edge_hole_points)++;
    }
  });
}

SampleView DepthMonitor::Impl::look_at(const cv::Mat& depth_mm, const Eigen::Vector3d& ground_point) const {
  const auto pixel = camera.project(ground_point);
  if (!pixel) return SampleView::kNoReading;
  const int u = static_cast<int>(std::lround(pixel->x())), v = static_cast<int>(std::lround(pixel->y()));
  if (u < 1 || v < 1 || u >= size.width - 1 || v >= size.height - 1) return SampleView::kNoReading;
  // Median of the valid readings around the pixel: robust to dropouts and speckle.
  std::array<uint16_t, 9> readings{};
  size_t n = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const uint16_t d = depth_mm.at<uint16_t>(v + dv, u + du);
      if (d >= min_range * 1000.0 && d <= max_range * 1000.0) readings[n++] = d;
    }
  if (n < 3) return SampleView::kNoReading;
  std::nth_element(readings.begin(), readings.begin() + n / 2, readings.begin() + n);
  const float depth = readings[n / 2] * 0.001f;
  const Eigen::Vector3f hit = origin + depth * directions[static_cast<size_t>(v * size.width + u)];
  if (hit.z() < -config.hole_min_depth) return SampleView::kHole;
  // A low hit short of the sample may be the foot of a tall object standing
  // on the sample: only a hit at the sample itself shows its ground.
  const float range = (ground_point.cast<float>() - origin).norm();
  const double tolerance = config.ground_match_tolerance + 3.0 * config.depth_noise_coefficient * range * range;
  const double miss = std::hypot(hit.x() - ground_point.x(), hit.y() - ground_point.y());
  if (hit.z() < config.obstacle_min_height && miss <= tolerance) return SampleView::kSeen;
  return SampleView::kHidden;
}

int8_t DepthMonitor::Impl::verdict(const CellEvidence& e) const {
  if (e.obstacle_points >= config.min_obstacle_points || e.hole_points >= config.min_hole_points ||
      e.samples_holes >= config.min_hole_samples)
    return obstacle_grid_t::STATE_OBSTACLE;
  if (e.obstacle_points + e.edge_obstacle_points >= config.min_obstacle_points ||
      e.hole_points + e.edge_hole_points >= config.min_hole_points)
    return obstacle_grid_t::STATE_UNKNOWN;  // an obstacle right at the footprint's edge
  if (e.samples_hidden == 0 && e.samples_seen >= config.min_seen_fraction * e.samples_total)
    return obstacle_grid_t::STATE_FREE;
  return obstacle_grid_t::STATE_UNKNOWN;
}

void DepthMonitor::evaluate(const cv::Mat& depth_mm, const QueryGrid& grid, obstacle_grid_t& out,
                            std::vector<CellEvidence>* evidence) const {
  const Impl& m = *impl_;
  if (depth_mm.type() != CV_16UC1 || depth_mm.size() != m.size)
    throw ImageError("depth image is " + std::to_string(depth_mm.cols) + "x" + std::to_string(depth_mm.rows) +
                     (depth_mm.type() == CV_16UC1 ? "" : " (not 16-bit mm)") + ", the calibrated depth sensor is " +
                     std::to_string(m.size.width) + "x" + std::to_string(m.size.height));
  const QueryGridConfig& g = grid.config();
  const double r = g.safety_radius;
  const auto cloud = m.cloud_near(depth_mm, grid);
  // Bins of side >= r: every point within r of a cell is in its 3x3 bins.
  const double bin = std::max(r, 1e-3);
  const double span_x = (grid.num_x() - 1) * g.spacing + 2 * r, span_y = (grid.num_y() - 1) * g.spacing + 2 * r;
  PointBins bins(g.x_min - r, g.y_min - r, bin, static_cast<int>(std::ceil(span_x / bin)) + 1,
                 static_cast<int>(std::ceil(span_y / bin)) + 1);
  for (const auto& p : *cloud) bins.add(p);

  out.state.assign(static_cast<size_t>(grid.size()), obstacle_grid_t::STATE_UNKNOWN);
  if (evidence) evidence->assign(static_cast<size_t>(grid.size()), CellEvidence{});
  for (int i = 0; i < grid.size(); ++i) {
    const QueryCell& cell = grid.cell(i);
    CellEvidence e;
    m.count_points(bins, cell, r, e);
    for (const auto& offset : kSampleOffsets) {
      const Eigen::Vector3d ground(cell.x + offset[0] * r, cell.y + offset[1] * r, 0.0);
      ++e.samples_total;
      switch (m.look_at(depth_mm, ground)) {
        case SampleView::kSeen: ++e.samples_seen; break;
        case SampleView::kHidden: ++e.samples_hidden; break;
        case SampleView::kHole: ++e.samples_holes; break;
        case SampleView::kNoReading: break;
      }
    }
    out.state[static_cast<size_t>(i)] = m.verdict(e);
    if (evidence) (*evidence)[static_cast<size_t>(i)] = e;
  }
}

}  // namespace ivoa::monitor
