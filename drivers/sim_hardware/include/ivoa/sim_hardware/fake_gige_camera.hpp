#pragma once
// A GigE Vision camera simulated by Aravis (ArvGvFakeCamera): real GVCP and
// GVSP on a local address, serving a StereoScene instead of Aravis' ramp.
// Two of them on 127.0.0.1 and 127.0.0.2 are a stereo rig the real driver
// opens and streams from, over the real network stack.
#include <arv.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "ivoa/sim_hardware/stereo_scene.hpp"

namespace ivoa::sim_hardware {

// Fills the buffers of an Aravis fake camera (GigE or the in-process "Fake"
// interface) with a scene. The tick shown is the frame time in frame periods
// when free-running (two cameras at one rate fire together, so a true pair
// shows one tick) and the frame id in software-trigger mode (one trigger,
// one frame per camera); frames fired more than a quarter period off their
// slot are stamped "off beat". The fake camera must stop (be destroyed) before
// its filler is.
class SceneFiller {
 public:
  SceneFiller(const StereoScene& scene, RigCamera camera, ArvFakeCamera* fake);
  SceneFiller(const SceneFiller&) = delete;
  SceneFiller& operator=(const SceneFiller&) = delete;

  int64_t frames() const { return frames_; }
  int64_t off_beat_frames() const { return off_beat_; }

 private:
  static void fill(ArvBuffer* buffer, void* self, guint32 exposure_us, guint32 gain, ArvPixelFormat format);
  FrameStamp stamp_of(ArvBuffer* buffer);

  const StereoScene& scene_;
  const RigCamera camera_;
  ArvFakeCamera* fake_;
  std::atomic<int64_t> frames_{0};
  std::atomic<int64_t> off_beat_{0};
  std::atomic<bool> warned_format_{false};
};

struct FakeGigeCameraOptions {
  std::string address;           // local IPv4 address to serve on; it must exist on an interface
  std::string serial;            // serial number the camera reports (its Aravis id is Aravis-Fake-<serial>)
  std::string genicam_xml;       // a custom GenICam description; empty = Aravis' own
  double packet_loss = 0;        // fraction of GVSP packets never sent (the fake never resends)
  double trigger_poll_hz = 100;  // how often a software trigger is looked for (latency 1/rate)
};

class FakeGigeCamera {
 public:
  // Throws std::runtime_error if the camera cannot serve on the address.
  FakeGigeCamera(const StereoScene& scene, RigCamera camera, const FakeGigeCameraOptions& options);
  ~FakeGigeCamera();
  FakeGigeCamera(const FakeGigeCamera&) = delete;
  FakeGigeCamera& operator=(const FakeGigeCamera&) = delete;

  int64_t frames() const { return filler_ ? filler_->frames() : 0; }
  int64_t off_beat_frames() const { return filler_ ? filler_->off_beat_frames() : 0; }

 private:
  ArvGvFakeCamera* gv_ = nullptr;
  std::unique_ptr<SceneFiller> filler_;
};

}  // namespace ivoa::sim_hardware
