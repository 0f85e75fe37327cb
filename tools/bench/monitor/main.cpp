// Depth monitor benchmark: ms per depth frame (640x480) for the default
// query grid on one core, on simulator frames from several scenes, next to
// a textbook baseline in the same run: the whole image as a point cloud,
// PCL's VoxelGrid, then a KD-tree radius search per cell.
#include <algorithm>
#include <cstdio>

#include <CLI/CLI.hpp>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/monitor/depth_monitor.hpp"
#include "ivoa/sim/simulator.hpp"
#include "ivoa/sim/trajectory.hpp"

using namespace ivoa;

namespace {

// The straightforward pipeline, for comparison: every valid pixel, voxel
// grid, then per cell count obstacle points within r with a KD-tree.
void baseline(const cv::Mat& depth, const RigCalibration& rig, const QueryGrid& grid, std::vector<int>& counts) {
  const CameraModel camera(rig.depth, rig.depth_to_robot);
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const uint16_t d = depth.at<uint16_t>(v, u);
      if (d == 0) continue;
      const Eigen::Vector3d p = camera.unproject({u, v}, d * 0.001);
      cloud->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
    }
  pcl::PointCloud<pcl::PointXYZ> filtered;
  pcl::VoxelGrid<pcl::PointXYZ> voxel;
  voxel.setLeafSize(0.02f, 0.02f, 0.02f);
  voxel.setInputCloud(cloud);
  voxel.filter(filtered);
  auto flat = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(filtered);
  for (auto& p : *flat) p.z = 0;  // horizontal distance
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(flat);
  std::vector<int> idx;
  std::vector<float> dist;
  counts.assign(static_cast<size_t>(grid.size()), 0);
  for (int i = 0; i < grid.size(); ++i) {
    const auto& c = grid.cell(i);
    tree.radiusSearch(pcl::PointXYZ(float(c.x), float(c.y), 0), float(grid.config().safety_radius), idx, dist);
    for (int k : idx) counts[static_cast<size_t>(i)] += filtered[static_cast<size_t>(k)].z > 0.05f;
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct MonitorTimes {
  std::vector<double> ours, baseline;  // median ms per frame
  int cells = 0;
};

// Times both on `frames` depth frames along the scene's drive. Throws on a
// scene file that cannot be loaded.
void time_scene(const std::string& name, int frames, int repeats, MonitorTimes& times) {
  const sim::Scene scene =
      sim::generate_scene(sim::load_scene_spec(std::string(IVOA_SCENES_DIR) + "/" + name + ".yaml"), 5);
  const sim::Simulator simulator(scene);
  sim::Trajectory trajectory(scene, 5);
  const QueryGrid grid(QueryGridConfig{}, RigGeometry(simulator.rig()).left);
  const monitor::DepthMonitor monitor(simulator.rig());
  times.cells = grid.size();
  for (int f = 0; f < frames; ++f) {
    const cv::Mat depth = simulator.render(trajectory.pose_at(3.0 * f + 1), static_cast<uint64_t>(f)).depth_mm;
    obstacle_grid_t out = make_obstacle_grid(grid, "depth_monitor", 0);
    std::vector<double> a, b;
    std::vector<int> counts;
    for (int r = 0; r < repeats; ++r) {
      double t = monotonic_ms();
      monitor.evaluate(depth, grid, out);
      a.push_back(monotonic_ms() - t);
      t = monotonic_ms();
      baseline(depth, simulator.rig(), grid, counts);
      b.push_back(monotonic_ms() - t);
    }
    times.ours.push_back(median(a));
    times.baseline.push_back(median(b));
  }
}

void print_times(const MonitorTimes& t) {
  const double o = median(t.ours), b = median(t.baseline);
  std::printf("Depth monitor, 640x480 depth frames from 5 simulated scenes (%zu frames), %d query cells, one core:\n",
              t.ours.size(), t.cells);
  std::printf("  %-66s median %6.2f ms, max %6.2f ms\n",
              "ours: region-cropped cloud, voxel grid, binned disc + ray samples", o,
              *std::max_element(t.ours.begin(), t.ours.end()));
  std::printf("  %-66s median %6.2f ms, max %6.2f ms\n",
              "baseline: whole-image cloud, VoxelGrid, KD-tree radius search", b,
              *std::max_element(t.baseline.begin(), t.baseline.end()));
  std::printf("  ratio baseline/ours %.1fx; budget 10 ms: %s (%.2f of budget)\n", b / o, o <= 10 ? "met" : "NOT met",
              o / 10);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Depth monitor benchmark (one core)"};
  int frames_per_scene = 4, repeats = 5;
  app.add_option("--frames-per-scene", frames_per_scene, "frames timed in each of the five scenes")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--repeats", repeats, "timings per frame (median kept)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;

  MonitorTimes times;
  for (const char* name : {"indoor_office", "corridor", "polished_lobby", "outdoor_campus", "wet_parking_lot"}) {
    try {
      time_scene(name, frames_per_scene, repeats, times);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "ivoa-bench-monitor: scene '%s': %s\n", name, e.what());
      return kExitBadInput;
    }
  }
  print_times(times);
  return kExitOk;
}
