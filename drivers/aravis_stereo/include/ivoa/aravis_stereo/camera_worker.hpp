#pragma once
// Runs one camera on its own thread: opens it (retrying with back-off),
// forwards its frames to the EventQueue, sends software triggers, and when
// no frame has come for `frame_timeout_s` (unplugged, powered off, network
// down) closes it and reopens it. The thread owns the camera: camera
// libraries such as Aravis are not thread-safe per camera object.
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "ivoa/aravis_stereo/camera_events.hpp"
#include "ivoa/aravis_stereo/camera_source.hpp"
#include "ivoa/aravis_stereo/reconnect_backoff.hpp"

namespace ivoa::aravis_stereo {

struct WorkerOptions {
  double frame_timeout_s = 2.0;  // no frame (complete or not) for this long = camera lost
  BackoffOptions backoff;        // waits between attempts to reopen
};

class CameraWorker {
 public:
  CameraWorker(Side side, std::unique_ptr<CameraSource> source, const WorkerOptions& options, EventQueue& events);
  ~CameraWorker();
  CameraWorker(const CameraWorker&) = delete;
  CameraWorker& operator=(const CameraWorker&) = delete;

  void start();
  // Asks the thread to close the camera and end; returns at once, so that
  // two cameras close in parallel.
  void request_stop();
  // request_stop() and waits for the thread. Closing an unreachable camera
  // waits for its own timeouts (Aravis: several seconds).
  void stop();
  // Asks the camera thread to fire a software trigger.
  void trigger();

  bool connected() const { return connected_; }
  int64_t disconnects() const { return disconnects_; }  // closed for want of frames or control
  int64_t reconnects() const { return reconnects_; }    // opened again after that

 private:
  void run();
  bool open_camera();
  void close_camera(const std::string& reason);
  void wait_for(double seconds);
  bool stop_requested();
  void on_frame(FrameResult&& result);

  const Side side_;
  std::unique_ptr<CameraSource> source_;
  const WorkerOptions options_;
  EventQueue& events_;
  ReconnectBackoff backoff_;

  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool trigger_requested_ = false;
  std::atomic<bool> connected_{false};
  std::atomic<int64_t> disconnects_{0}, reconnects_{0};
  std::atomic<double> last_frame_ms_{0};
  std::atomic<bool> frame_since_open_{false};  // set on the stream's thread
  double lost_at_ms_ = -1;
  bool lost_after_a_frame_ = false;
};

}  // namespace ivoa::aravis_stereo
