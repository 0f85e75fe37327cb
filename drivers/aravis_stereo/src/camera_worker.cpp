#include "ivoa/aravis_stereo/camera_worker.hpp"

#include <spdlog/spdlog.h>

#include "ivoa/core/time.hpp"

namespace ivoa::aravis_stereo {
namespace {

// How often the thread checks for silence when nothing else wakes it.
constexpr auto kPollInterval = std::chrono::milliseconds(50);

CameraEvent status_event(CameraEvent::Type type, Side side, std::string detail) {
  CameraEvent event;
  event.type = type;
  event.side = side;
  event.detail = std::move(detail);
  return event;
}

}  // namespace

CameraWorker::CameraWorker(Side side, std::unique_ptr<CameraSource> source, const WorkerOptions& options,
                           EventQueue& events)
    : side_(side), source_(std::move(source)), options_(options), events_(events), backoff_(options.backoff) {}

CameraWorker::~CameraWorker() { stop(); }

void CameraWorker::start() {
  if (thread_.joinable()) return;
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
}

void CameraWorker::request_stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
}

void CameraWorker::stop() {
  request_stop();
  if (thread_.joinable()) thread_.join();
}

void CameraWorker::trigger() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    trigger_requested_ = true;
  }
  wake_.notify_all();
}

void CameraWorker::on_frame(FrameResult&& result) {
  last_frame_ms_ = monotonic_ms();
  frame_since_open_ = true;
  CameraEvent event;
  event.side = side_;
  if (result.complete) {
    event.type = CameraEvent::Type::kFrame;
    event.frame = std::move(result.frame);
  } else {
    event.type = CameraEvent::Type::kIncomplete;
    event.detail = std::move(result.problem);
  }
  events_.push(std::move(event));
}

bool CameraWorker::stop_requested() {
  std::lock_guard<std::mutex> lock(mutex_);
  return stopping_;
}

void CameraWorker::wait_for(double seconds) {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return stopping_; });
}

bool CameraWorker::open_camera() {
  frame_since_open_ = false;  // before start(): its first frames may come before start() returns
  try {
    source_->start([this](FrameResult&& r) { on_frame(std::move(r)); });
  } catch (const CameraConfigError& e) {
    spdlog::error("{}: {}", source_->describe(), e.what());
    events_.push(status_event(CameraEvent::Type::kFatal, side_, e.what()));
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    return false;
  } catch (const std::exception& e) {
    if (stop_requested()) {  // the driver gave up while this attempt ran: no retry follows
      spdlog::warn("{}: cannot open: {}", source_->describe(), e.what());
      return false;
    }
    const double delay = backoff_.next_delay_s();
    spdlog::warn("{}: cannot open: {}; retrying in {:.1f} s (attempt {})", source_->describe(), e.what(), delay,
                 backoff_.failures());
    wait_for(delay);
    return false;
  }
  connected_ = true;
  last_frame_ms_ = monotonic_ms();
  if (lost_at_ms_ >= 0) {
    ++reconnects_;
    spdlog::info("{}: reconnected, {:.1f} s after {}", source_->describe(), (monotonic_ms() - lost_at_ms_) / 1000.0,
                 lost_after_a_frame_ ? "its last frame" : "it was opened and sent no frame");
  }
  lost_at_ms_ = -1;
  backoff_.succeeded();
  events_.push(status_event(CameraEvent::Type::kConnected, side_, source_->describe()));
  return true;
}

void CameraWorker::close_camera(const std::string& reason) {
  spdlog::warn("{}: {}; closing it and reconnecting", source_->describe(), reason);
  events_.push(status_event(CameraEvent::Type::kDisconnected, side_, reason));
  connected_ = false;
  ++disconnects_;
  lost_at_ms_ = last_frame_ms_;  // the images stopped then, not now
  lost_after_a_frame_ = frame_since_open_;
  source_->abandon();
}

void CameraWorker::run() {
  while (!stop_requested()) {
    if (!connected_) {
      open_camera();
      continue;
    }
    bool fire = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait_for(lock, kPollInterval, [this] { return stopping_ || trigger_requested_; });
      if (stopping_) break;
      fire = trigger_requested_;
      trigger_requested_ = false;
    }
    if (fire) {
      try {
        source_->software_trigger();
      } catch (const std::exception& e) {
        close_camera(std::string("software trigger failed: ") + e.what());
        continue;
      }
    }
    const double silent_s = (monotonic_ms() - last_frame_ms_) / 1000.0;
    if (source_->control_lost()) close_camera("lost control of the camera (heartbeat failed)");
    else if (silent_s > options_.frame_timeout_s)
      close_camera("no frame for " + fmt::format("{:.1f}", silent_s) + " s");
  }
  if (connected_) source_->stop();
  connected_ = false;
}

}  // namespace ivoa::aravis_stereo
