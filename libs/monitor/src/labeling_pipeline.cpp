#include "ivoa/monitor/labeling_pipeline.hpp"

#include "ivoa/core/camera_model.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/monitor/labeler.hpp"

namespace ivoa::monitor {

LabelingPipeline::LabelingPipeline(const RigCalibration& rig, const QueryGridConfig& grid_config,
                                   const DepthMonitorConfig& monitor_config, const PairingConfig& pairing)
    : rig_(rig), grid_(grid_config, RigGeometry(rig).left), monitor_(rig, monitor_config), pairer_(pairing) {}

std::vector<PipelineOutcome> LabelingPipeline::add_depth(int64_t utime, cv::Mat depth_mm) {
  if (depth_mm.type() != CV_16UC1 || depth_mm.cols != rig_.depth.width || depth_mm.rows != rig_.depth.height)
    throw ImageError("depth image is " + std::to_string(depth_mm.cols) + "x" + std::to_string(depth_mm.rows) +
                     ", the calibrated depth sensor is " + std::to_string(rig_.depth.width) + "x" +
                     std::to_string(rig_.depth.height));
  return finish(pairer_.add_depth(utime, std::move(depth_mm)));
}

std::vector<PipelineOutcome> LabelingPipeline::add_stereo(obstacle_grid_t stereo_grid) {
  if (const std::string why = grid_content_error(stereo_grid); !why.empty())
    throw LabelError("stereo grid from '" + stereo_grid.detector + "': " + why);
  if (const std::string why = geometry_mismatch(stereo_grid, grid_); !why.empty())
    throw LabelError("stereo grid from '" + stereo_grid.detector + "' does not match the configured grid: " + why);
  const int64_t utime = stereo_grid.utime;
  return finish(pairer_.add_stereo(utime, std::move(stereo_grid)));
}

std::vector<PipelineOutcome> LabelingPipeline::flush() { return finish(pairer_.flush()); }

std::vector<PipelineOutcome> LabelingPipeline::finish(
    std::vector<FramePairer<cv::Mat, obstacle_grid_t>::Result> results) {
  std::vector<PipelineOutcome> out;
  out.reserve(results.size());
  for (auto& r : results) {
    PipelineOutcome o;
    o.stereo_utime = r.stereo_utime;
    o.stereo_grid = std::move(r.stereo);
    o.nearest_depth_us = r.nearest_depth_us;
    if (r.depth) {
      LabeledFrame f;
      const double start = monotonic_ms();
      f.depth_grid = make_obstacle_grid(grid_, "depth_monitor", o.stereo_utime);
      f.depth_grid.depth_utime = *r.depth_utime;
      monitor_.evaluate(*r.depth, grid_, f.depth_grid);
      f.monitor_ms = monotonic_ms() - start;
      f.depth_grid.compute_ms = f.monitor_ms;
      f.labels = label_frame(o.stereo_grid, f.depth_grid);
      o.labeled = std::move(f);
    }
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace ivoa::monitor
