#include "introspection_node.hpp"

#include <algorithm>
#include <future>
#include <limits>
#include <utility>

#include <opencv2/core.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/stop_signal.hpp"
#include "ivoa/core/time.hpp"
#include "ivoa/introspection_labels_t.hpp"

namespace ivoa {
namespace {

constexpr const char* kFramesUntrainedSize = "frames_untrained_size";

std::vector<float> flatten(const cv::Mat& m) { return std::vector<float>(m.begin<float>(), m.end<float>()); }

// The query cell's prediction given the detector's verdict there (unknown:
// the verdict fields say so).
void add_verdict(introspection_t& msg, const introspection::Prediction& p, int8_t state, double threshold) {
  msg.query_verdict.push_back(state);
  if (state != obstacle_grid_t::STATE_OBSTACLE && state != obstacle_grid_t::STATE_FREE) {
    msg.query_verdict_class.push_back(introspection_labels_t::LABEL_NONE);
    msg.query_p_wrong.push_back(std::numeric_limits<float>::quiet_NaN());
    msg.query_p_wrong_variance.push_back(std::numeric_limits<float>::quiet_NaN());
    msg.query_verdict_announced.push_back(0);
    return;
  }
  const auto v = introspection::given_verdict(p, state == obstacle_grid_t::STATE_OBSTACLE, threshold);
  msg.query_verdict_class.push_back(static_cast<int8_t>(v.predicted));
  msg.query_p_wrong.push_back(v.p_wrong);
  msg.query_p_wrong_variance.push_back(v.variance);
  msg.query_verdict_announced.push_back(v.announced ? 1 : 0);
}

// The grid's cells in view, in grid order, with their predictions and,
// where the grid is this frame's, the prediction given its verdict.
void add_query_cells(introspection_t& msg, const introspection::IntrospectionModel& model, const obstacle_grid_t& grid,
                     const std::vector<introspection::Prediction>& predictions, bool grid_is_this_frames) {
  size_t next = 0;
  for (size_t i = 0; i < grid.state.size(); ++i) {
    if (!grid.in_image[i]) continue;
    const auto& p = predictions.at(next++);
    msg.query_x.push_back(grid.x[i]);
    msg.query_y.push_back(grid.y[i]);
    msg.query_u.push_back(grid.u[i]);
    msg.query_v.push_back(grid.v[i]);
    msg.query_class.push_back(static_cast<int8_t>(p.predicted));
    msg.query_probability.push_back(p.probability[static_cast<size_t>(p.predicted)]);
    msg.query_uncertainty.push_back(p.variance);
    msg.query_announced.push_back(p.announced ? 1 : 0);
    add_verdict(msg, p, grid_is_this_frames ? grid.state[i] : obstacle_grid_t::STATE_UNKNOWN,
                model.verdict_threshold());
  }
}

}  // namespace

void RecentGrids::put(const obstacle_grid_t& grid) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    grids_.push_back(grid);
    if (grids_.size() > kept_) grids_.pop_front();
  }
  arrived_.notify_all();
}

void RecentGrids::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  arrived_.notify_all();
}

std::optional<obstacle_grid_t> RecentGrids::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (grids_.empty()) return std::nullopt;
  return grids_.back();
}

std::optional<obstacle_grid_t> RecentGrids::of_frame(int64_t utime, std::chrono::milliseconds wait) {
  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<obstacle_grid_t> found;
  arrived_.wait_for(lock, wait, [&] {
    for (auto it = grids_.rbegin(); it != grids_.rend(); ++it)
      if (it->utime == utime) {
        found = *it;
        return true;
      }
    // A newer frame's grid, or no more grids: this frame's will not come.
    return closed_ || (!grids_.empty() && grids_.back().utime > utime);
  });
  return found;
}

std::vector<introspection::Prediction> query_predictions(introspection::IntrospectionModel& model,
                                                         const introspection::Heatmaps& h, const cv::Mat& input,
                                                         const obstacle_grid_t& grid) {
  const auto& info = model.info();
  const std::vector<int> sides =
      footprint_patch_sides(grid, info.patch_size, cv::Size(input.cols, input.rows / info.views), info.patch_scale);
  std::vector<introspection::IntrospectionModel::CellPatch> cells;
  for (size_t i = 0; i < grid.state.size(); ++i)
    if (grid.in_image[i]) cells.push_back({grid.u[i], grid.v[i], sides[i]});
  return model.predict_query_cells(input, h, cells);
}

introspection_t make_introspection_message(const introspection::IntrospectionModel& model,
                                           const introspection::Heatmaps& h, int64_t utime, int image_width,
                                           int image_height, const obstacle_grid_t* grid,
                                           const std::vector<introspection::Prediction>& predictions, int mc_passes,
                                           bool grid_is_this_frames) {
  introspection_t msg;
  msg.utime = utime;
  msg.model_id = model.info().id;
  msg.mc_passes = mc_passes;
  msg.uncertainty_threshold = static_cast<float>(model.uncertainty_threshold());
  msg.verdict_uncertainty_threshold = static_cast<float>(model.verdict_threshold());
  msg.image_width = image_width;
  msg.image_height = image_height;
  msg.patch_size = h.patch_size;
  msg.stride = h.stride;
  msg.rows = h.rows;
  msg.cols = h.cols;
  msg.prob_tp = flatten(h.probability[0]);
  msg.prob_tn = flatten(h.probability[1]);
  msg.prob_fp = flatten(h.probability[2]);
  msg.prob_fn = flatten(h.probability[3]);
  msg.uncertainty = flatten(h.uncertainty);
  msg.class_variance = flatten(h.predicted_variance);
  if (grid) add_query_cells(msg, model, *grid, predictions, grid_is_this_frames);
  msg.compute_ms = h.compute_ms;
  return msg;
}

double warm_up(introspection::IntrospectionModel& model, cv::Size image_size, int near_cells) {
  const double start = monotonic_ms();
  const cv::Mat blank(image_size.height * model.info().views, image_size.width, CV_8UC3, cv::Scalar::all(128));
  model.run(blank);
  const int side = std::min({2 * model.info().patch_size, image_size.width, image_size.height});
  if (model.info().patch_scale > 0 && side > model.info().patch_size) {
    const std::vector<introspection::IntrospectionModel::CellPatch> cells(
        static_cast<size_t>(near_cells), {image_size.width / 2.0, image_size.height - side / 2.0, side});
    model.predict_cells(blank, cells);
  }
  return monotonic_ms() - start;
}

cv::Size default_warm_up_size(const introspection::ModelInfo& info) {
  return info.image_sizes.empty() ? cv::Size(960, 600) : info.image_sizes.front();
}

IntrospectionNode::IntrospectionNode(Bus& bus, Heartbeat& heartbeat,
                                     std::unique_ptr<introspection::IntrospectionModel> model,
                                     IntrospectionNodeOptions options, int mc_passes)
    : bus_(bus),
      heartbeat_(heartbeat),
      model_(std::move(model)),
      options_(std::move(options)),
      mc_passes_(mc_passes),
      frames_(static_cast<size_t>(std::max(options_.queue_frames, 1))),
      grids_(static_cast<size_t>(std::max(options_.queue_frames, 1)) + 16) {
  bus_.on_decode_error([this](const std::string& what) { heartbeat_.bad_input(what); });
  heartbeat_.set_counter(kFramesMissed, 0);
  if (!model_->info().image_sizes.empty()) heartbeat_.set_counter(kFramesUntrainedSize, 0);
  bus_.subscribe<stereo_image_t>(options_.stereo_channel, [this](const stereo_image_t& m, const ReceiveInfo&) {
    heartbeat_.count_in();
    heartbeat_.add_to_counter(kFramesMissed, missed_.add(m.seq));
    const uint64_t dropped_before = frames_.dropped();
    frames_.put({m, monotonic_ms()});
    if (frames_.dropped() != dropped_before) heartbeat_.count_dropped();  // the status table's DROP column
  });
  if (model_->info().views == 2) {
    calibration_wait_.emplace(heartbeat_, options_.calibration_channel);
    if (options_.initial_calibration) {  // the worker builds its warp before the first frame
      calibrations_.take(*options_.initial_calibration);
      new_rig_ = options_.initial_calibration;
      new_rig_source_ =
          options_.initial_calibration_file.empty() ? "the --calibration file" : options_.initial_calibration_file;
    }
    bus_.subscribe<rig_calibration_t>(options_.calibration_channel,
                                      [this](const rig_calibration_t& m, const ReceiveInfo&) { on_calibration(m); });
  }
  if (!options_.grid_channel.empty())
    bus_.subscribe<obstacle_grid_t>(options_.grid_channel,
                                    [this](const obstacle_grid_t& m, const ReceiveInfo&) { on_grid(m); });
  std::promise<void> warm;
  std::future<void> warmed = warm.get_future();
  worker_ = std::thread([this, &warm] {
    warm_up_worker();
    warm.set_value();
    work();
  });
  warmed.wait();
  heartbeat_.set_state("running");
}

IntrospectionNode::~IntrospectionNode() { stop(); }

void IntrospectionNode::stop() {
  grids_.close();  // called once LCM is no longer handled: the frames left need not wait for theirs
  frames_.close();
  if (worker_.joinable()) worker_.join();
}

void IntrospectionNode::warm_up_worker() {
  if (!options_.warm_up) return;
  try {
    const double ms = warm_up(*model_, *options_.warm_up);
    spdlog::info("warmed up on a blank {}x{} frame in {:.0f} ms", options_.warm_up->width, options_.warm_up->height,
                 ms);
  } catch (const std::exception& e) {  // the first real frame pays for the set-up instead
    spdlog::warn("warm-up on a blank {}x{} frame failed: {}", options_.warm_up->width, options_.warm_up->height,
                 e.what());
  }
}

// Once closed, the frames left in the mailbox are still run (take() returns
// at once): a frame received is published or counted as dropped, never lost.
void IntrospectionNode::work() {
  while (true) {
    update_warp();  // as soon as a calibration is in, so the first frame does not wait for it
    auto frame = frames_.take(std::chrono::milliseconds(100));
    if (!frame) {
      if (frames_.closed()) return;
      continue;
    }
    process(*frame);
    heartbeat_.set_counter("frames_done", frames_done_.load());
  }
}

void IntrospectionNode::on_calibration(const rig_calibration_t& msg) {
  std::lock_guard<std::mutex> lock(calibration_mutex_);
  try {
    if (std::optional<RigCalibration> rig = calibrations_.take_if_new(msg)) {
      new_rig_ = std::move(rig);
      new_rig_source_ = options_.calibration_channel;
    }
  } catch (const CalibrationError& e) {
    heartbeat_.bad_input(options_.calibration_channel + ": " + e.what());
  }
}

void IntrospectionNode::on_grid(obstacle_grid_t grid) {
  if (const std::string why = grid_content_error(grid); !why.empty()) {
    heartbeat_.bad_input(options_.grid_channel + " utime " + std::to_string(grid.utime) + ": " + why);
    return;
  }
  const std::string& own = model_->info().detector;
  if (!grid.detector.empty() && !own.empty() && grid.detector != own) {
    if (!std::exchange(warned_other_detector_, true))
      spdlog::warn(
          "{}: grids from the '{}' detector, but model {} was trained for '{}': no predictions given "
          "their verdicts (counted as grids_other_detector)",
          options_.grid_channel, grid.detector, model_->info().id, own);
    heartbeat_.add_to_counter("grids_other_detector", 1);
    std::fill(grid.state.begin(), grid.state.end(), obstacle_grid_t::STATE_UNKNOWN);
  }
  grids_.put(grid);
}

// A calibration the warp cannot be built for (OpenCV refuses it, or its
// maps do not fit in memory) is bad input; the warp built before stays.
void IntrospectionNode::update_warp() {
  std::optional<RigCalibration> rig;
  std::string source;
  {
    std::lock_guard<std::mutex> lock(calibration_mutex_);
    rig = std::exchange(new_rig_, std::nullopt);
    source = new_rig_source_;
  }
  if (!rig) return;
  try {
    warp_ = std::make_unique<GroundWarp>(*rig);  // outside the lock: 0.4 s for 960x600 on a slow core
    spdlog::info("ground warp built for calibration '{}' from {}", rig->rig_name, source);
  } catch (const std::exception& e) {
    heartbeat_.bad_input(source + ": cannot use calibration '" + rig->rig_name + "': " + e.what() +
                         (warp_ ? " (the one before stays)" : ""));
  }
}

void IntrospectionNode::check_image_size(cv::Size size) {
  if (introspection::trained_on_size(model_->info(), size)) return;
  heartbeat_.add_to_counter(kFramesUntrainedSize, 1);
  if (std::find(warned_sizes_.begin(), warned_sizes_.end(), size) != warned_sizes_.end()) return;
  warned_sizes_.push_back(size);
  spdlog::warn(
      "{}: {}x{} images, but model {} was trained on {} images: it runs (patches are cut on the ground and "
      "resized), but how well it predicts this camera's failures is unmeasured. Record this rig "
      "(procman_configs/record.pmd), build a dataset from the logs (ivoa-dataset build) and fine-tune on it "
      "(ivoa-train --init <this model>). Such frames are counted as {}.",
      options_.stereo_channel, size.width, size.height, model_->info().id,
      introspection::image_sizes_text(model_->info().image_sizes), kFramesUntrainedSize);
}

cv::Mat IntrospectionNode::model_input(const Frame& frame, const std::string& where, cv::Mat& left) {
  if (const std::string why = stereo_times_error(frame.msg); !why.empty()) {
    heartbeat_.bad_input(where + ": " + why);
    return {};
  }
  try {
    left = decode_image(frame.msg.left);
  } catch (const std::exception& e) {  // ImageError, or OpenCV's
    heartbeat_.bad_input(where + ": left image: " + e.what());
    return {};
  }
  if (model_->info().views == 1) return left;
  update_warp();
  if (!warp_) {
    calibration_wait_->skip(where, ", which a two-view model needs");
    return {};
  }
  calibration_wait_->end();
  cv::Mat right;
  try {
    right = decode_image(frame.msg.right);
  } catch (const std::exception& e) {
    heartbeat_.bad_input(where + ": right image: " + e.what());
    return {};
  }
  try {
    return warp_->stack(left, right);
  } catch (const std::exception& e) {  // ImageError: sizes the calibration does not have
    heartbeat_.bad_input(where + ": " + e.what());
    return {};
  }
}

void IntrospectionNode::process(const Frame& frame) {
  const std::string where = options_.stereo_channel + " utime " + std::to_string(frame.msg.utime);
  cv::Mat left;
  const cv::Mat input = model_input(frame, where, left);
  if (input.empty()) return;
  check_image_size(left.size());
  introspection::Heatmaps h;
  std::vector<introspection::Prediction> predictions;
  std::optional<obstacle_grid_t> grid;
  bool grid_is_this_frames = false;
  try {
    h = model_->run(input);
    if (!options_.grid_channel.empty()) {
      grid = grids_.of_frame(frame.msg.utime, options_.grid_wait);
      grid_is_this_frames = grid.has_value();
      if (!grid) {
        grid = grids_.latest();  // the query cells' geometry; no verdicts
        heartbeat_.add_to_counter("grids_missing", 1);
      }
    }
    if (grid) predictions = query_predictions(*model_, h, input, *grid);
  } catch (const std::exception& e) {  // ModelError, or a grid whose arrays do not match its size
    heartbeat_.bad_input(where + ": " + e.what());
    return;
  }
  introspection_t msg =
      make_introspection_message(*model_, h, frame.msg.utime, left.cols, left.rows, grid ? &*grid : nullptr,
                                 predictions, mc_passes_, grid_is_this_frames);
  msg.compute_ms = monotonic_ms() - frame.received_ms;
  if (bus_.publish(options_.out_channel, msg)) heartbeat_.count_out();
  else heartbeat_.add_to_counter("publish_failures", 1);  // not counted as out
  heartbeat_.latency(msg.compute_ms);
  ++frames_done_;
}

}  // namespace ivoa
