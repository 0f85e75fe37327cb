#pragma once
// A depth sensor through OpenNI2: a live device (the first one, or one by
// URI) or an .oni recording, its depth stream (and optionally colour), with
// optional depth-to-colour registration and recording to an .oni file.
// A real Kinect v1 needs libfreenect's OpenNI2 driver (libFreenectDriver.so,
// built from source; Debian does not package it).
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "ivoa/openni2_kinect/depth_intrinsics.hpp"

namespace ivoa::openni2_kinect {

// The sensor cannot be used; exit_code says why (process.hpp codes).
class DeviceError : public std::runtime_error {
 public:
  DeviceError(const std::string& what, int exit_code) : std::runtime_error(what), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

// One frame cannot be read as the image it claims (a damaged recording):
// skipped and counted, the stream goes on.
class BadFrame : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct OpenNiOptions {
  std::string device = "ANY_DEVICE";  // ANY_DEVICE (the first device), a device URI, or an .oni file
  bool color = false;                 // also stream 640x480 RGB
  bool register_depth = false;        // depth-to-colour registration (depth in the colour camera's frame)
  double playback_speed = 1.0;        // .oni only: 1 = real time, <= 0 = as fast as possible
  bool loop = false;                  // .oni only: start again at the end instead of stopping
  std::string record_path;            // record the streams to this .oni file, never overwritten ("" = none)
  bool lossy_color = true;            // record colour as JPEG (about 30x smaller than lossless)
};

struct DepthFrame {
  cv::Mat depth_mm;     // CV_16UC1, millimetres, 0 = no reading
  int frame_index = 0;  // the device's counter
  uint64_t device_time_us = 0;
};

struct ColorFrame {
  cv::Mat rgb;  // CV_8UC3, R G B order as the sensor delivers it
  int frame_index = 0;
  uint64_t device_time_us = 0;
};

// True for an .oni recording (by name, or any regular file), not a device URI.
bool is_recording_path(const std::string& device);

class OpenNiCamera {
 public:
  // Initialises OpenNI2, opens the device, starts the streams (and the
  // recorder). Throws DeviceError: no device or driver (exit 1), an .oni
  // file that is missing or unreadable (exit 3), a recording that cannot
  // be written (exit 4). A recording whose file exists goes to the first
  // free "stem-N.oni" next to it instead. A depth mode or field of view no
  // sensor has is bad input (exit 3); a recording whose header is so
  // damaged leaves OpenNI2 as it is: the process must end with
  // std::_Exit, for OpenNI2's teardown of it could crash.
  explicit OpenNiCamera(const OpenNiOptions& options);
  ~OpenNiCamera();
  OpenNiCamera(const OpenNiCamera&) = delete;
  OpenNiCamera& operator=(const OpenNiCamera&) = delete;

  enum class Ready { kDepth, kColor, kTimeout, kEndOfRecording };
  // Waits up to timeout_ms for a frame.
  Ready wait(int timeout_ms);
  DepthFrame read_depth();  // after kDepth; throws BadFrame for one whose data does not hold its image
  ColorFrame read_color();  // after kColor; likewise

  // Intrinsics of the depth image from the reported field of view (the
  // colour camera's when registered); nothing if the device reports none.
  bool depth_fov_intrinsics(PinholeIntrinsics* out) const;
  int depth_width() const;
  int depth_height() const;
  bool registered() const;
  std::string description() const;
  // The file being recorded to (a numbered name if the one given existed); "" if none.
  std::string record_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ivoa::openni2_kinect
