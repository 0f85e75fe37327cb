#pragma once
// One camera of the stereo pair, behind an interface so the driver's
// threading, reconnection and pairing run the same with real cameras
// (AravisCamera) and with test doubles.
#include <functional>
#include <stdexcept>
#include <string>

#include "ivoa/aravis_stereo/camera_frame.hpp"

namespace ivoa::aravis_stereo {

// The camera cannot be reached or stopped answering: worth retrying.
class CameraError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The camera cannot do what was asked (pixel format, size, trigger source):
// retrying will not help. what() says what, not which camera: the worker
// logs it after the source's describe().
class CameraConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a camera delivered: a complete frame, or an incomplete one (lost or
// late packets) that must be dropped, with the reason.
struct FrameResult {
  bool complete = false;
  CameraFrame frame;    // pixels only when complete
  std::string problem;  // why it is incomplete
};

class CameraSource {
 public:
  using FrameCallback = std::function<void(FrameResult&&)>;
  virtual ~CameraSource() = default;

  // Opens and configures the camera and starts streaming. `on_frame` is
  // called from the source's own thread until stop() returns.
  // Throws CameraError or CameraConfigError.
  virtual void start(FrameCallback on_frame) = 0;
  // Stops streaming and closes the camera; safe to call when not started.
  virtual void stop() = 0;
  // Lets go of a camera that stopped answering without waiting for it (a
  // dead camera makes every command wait for its timeout): start() may be
  // called again at once.
  virtual void abandon() { stop(); }
  // Fires one frame in software-trigger mode. Throws CameraError.
  virtual void software_trigger() = 0;
  // True once the connection is known to be gone (e.g. heartbeat failed).
  virtual bool control_lost() const { return false; }
  // For log lines: "left camera 127.0.0.1".
  virtual std::string describe() const = 0;
};

}  // namespace ivoa::aravis_stereo
