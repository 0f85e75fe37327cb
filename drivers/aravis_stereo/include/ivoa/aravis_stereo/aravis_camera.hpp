#pragma once
// A GenICam camera (GigE Vision or USB3 Vision, e.g. FLIR/Point Grey
// Blackfly) through Aravis, as one side of the stereo pair.
#include <memory>
#include <string>

#include "ivoa/aravis_stereo/camera_source.hpp"

namespace ivoa::aravis_stereo {

struct AravisCameraConfig {
  std::string device;                     // IP address, Aravis id (Vendor-Model-Serial), serial number or MAC
  std::string pixel_format = "BayerRG8";  // GenICam PixelFormat: BayerRG8, BayerBG8, BayerGB8, BayerGR8, Mono8, RGB8
  int width = 0;                          // region of interest, pixels; 0 = keep the camera's
  int height = 0;
  int offset_x = 0;  // region origin, pixels
  int offset_y = 0;
  double frame_rate_hz = 30;     // free-running rate; 0 = keep the camera's
  double exposure_us = 0;        // fixed exposure, microseconds; 0 = continuous auto exposure
  double gain = -1;              // fixed gain (camera units, dB on FLIR); < 0 = continuous auto gain
  int packet_size = 0;           // GigE Vision packet size, bytes (9000 with jumbo frames); 0 = negotiate
  int64_t packet_delay_ns = 0;   // GigE Vision inter-packet delay; 0 = keep the camera's
  bool packet_resend = true;     // ask a GigE camera to resend lost packets
  int64_t throughput_limit = 0;  // DeviceLinkThroughputLimit, bytes/s, for cameras sharing a link; 0 = keep
  std::string trigger = "none";  // none | software | a hardware input line, e.g. Line0
  int buffers = 8;               // stream buffers in flight
};

class AravisCamera : public CameraSource {
 public:
  AravisCamera(Side side, AravisCameraConfig config);
  ~AravisCamera() override;

  void start(FrameCallback on_frame) override;
  void stop() override;
  // Releases the camera in a background thread (Aravis waits seconds for
  // each command to an unreachable camera); the destructor joins it.
  void abandon() override;
  void software_trigger() override;
  bool control_lost() const override;
  std::string describe() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The host-side network and stream set-up a GigE camera should get; exposed
// for the README and the --help text.
inline constexpr const char* kGigeTuningHint =
    "MTU 9000 on the camera's NIC, --packet-size 9000 (or 8192), net.core.rmem_max >= 32 MB";

}  // namespace ivoa::aravis_stereo
