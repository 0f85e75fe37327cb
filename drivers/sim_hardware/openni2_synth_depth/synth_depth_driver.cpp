// libIvoaSynthDepth.so.0: an OpenNI2 driver plugin that simulates a Kinect
// v1 (drivers_notes.md, Appendix A). One device, synth://ivoa/depth0, with
// a 640x480 DEPTH_1_MM stream (a wall at 2000 mm, a box at 1000 mm moving
// 1 px per frame, see synth_depth_scene.hpp) and a 640x480 RGB888 stream,
// field-of-view properties, depth-to-colour registration, and the STRIDE
// and CROPPING properties OpenNI2's Recorder stores so that its .oni files
// play back through the stock OniFile driver.
//
// OpenNI2 loads it from <dir of libOpenNI2.so.0>/OpenNI2/Drivers; the build
// makes such a private folder (build/oni_redist) for LD_LIBRARY_PATH.
// IVOA_SYNTH_DEPTH_FPS sets the frame rate (default 30).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>

// OniDriverAPI.h expects XnLib's allocation macros, which are not shipped.
#define XN_NEW(type, arg) new type(arg)
#define XN_DELETE(p) delete (p)
#include <Driver/OniDriverAPI.h>

#include "ivoa/sim_hardware/synth_depth_scene.hpp"

namespace {

namespace scene = ivoa::sim_hardware::synth_depth;
using oni::driver::DeviceBase;
using oni::driver::DriverBase;
using oni::driver::StreamBase;

constexpr const char* kDeviceUri = "synth://ivoa/depth0";

// OpenNI2 video modes count whole frames per second; anything else is said
// (the driver has no other channel to the user) and replaced by the default.
int frames_per_second() {
  const char* text = std::getenv("IVOA_SYNTH_DEPTH_FPS");
  if (text == nullptr) return scene::kFps;
  char* end = nullptr;
  const long fps = std::strtol(text, &end, 10);
  if (end != text && *end == '\0' && fps > 0 && fps <= 1000) return static_cast<int>(fps);
  std::fprintf(stderr, "ivoa synth depth: IVOA_SYNTH_DEPTH_FPS=%s is not a whole number of Hz in 1..1000; using %d\n",
               text, scene::kFps);
  return scene::kFps;
}

template <class T>
OniStatus put(const T& value, void* data, int* size) {
  if (*size < static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
  std::memcpy(data, &value, sizeof(T));
  *size = sizeof(T);
  return ONI_STATUS_OK;
}

class SynthStream : public StreamBase {
 public:
  SynthStream(OniSensorType type, const std::atomic<int>& registration, int fps)
      : type_(type), registration_(registration) {
    mode_.pixelFormat = type == ONI_SENSOR_DEPTH ? ONI_PIXEL_FORMAT_DEPTH_1_MM : ONI_PIXEL_FORMAT_RGB888;
    mode_.resolutionX = scene::kWidth;
    mode_.resolutionY = scene::kHeight;
    mode_.fps = fps;
  }
  ~SynthStream() override { stop(); }

  OniStatus start() override {
    if (running_) return ONI_STATUS_OK;
    running_ = true;
    thread_ = std::thread([this] { produce(); });
    return ONI_STATUS_OK;
  }

  void stop() override {
    running_ = false;
    if (thread_.joinable()) thread_.join();  // joined, so unloading the driver is safe
  }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case ONI_STREAM_PROPERTY_STRIDE:
      case ONI_STREAM_PROPERTY_CROPPING:
      case ONI_STREAM_PROPERTY_MIRRORING: return TRUE;
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE: return type_ == ONI_SENSOR_DEPTH;
      default: return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    const bool depth = type_ == ONI_SENSOR_DEPTH;
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE: return put(mode_, data, size);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return put(depth && !registered() ? scene::kDepthHfovRad : scene::kColorHfovRad, data, size);
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return put(depth && !registered() ? scene::kDepthVfovRad : scene::kColorVfovRad, data, size);
      case ONI_STREAM_PROPERTY_STRIDE: return put(stride_bytes(), data, size);
      case ONI_STREAM_PROPERTY_CROPPING: {
        OniCropping none{};
        return put(none, data, size);
      }
      case ONI_STREAM_PROPERTY_MIRRORING: return put(static_cast<OniBool>(FALSE), data, size);
      case ONI_STREAM_PROPERTY_MAX_VALUE: return depth ? put(10000, data, size) : ONI_STATUS_NOT_SUPPORTED;
      case ONI_STREAM_PROPERTY_MIN_VALUE: return depth ? put(0, data, size) : ONI_STATUS_NOT_SUPPORTED;
      default: return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  // Only the modes it already has: one resolution and format per sensor.
  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE && size == sizeof(OniVideoMode)) {
      const auto* mode = static_cast<const OniVideoMode*>(data);
      const bool same = mode->pixelFormat == mode_.pixelFormat && mode->resolutionX == mode_.resolutionX &&
                        mode->resolutionY == mode_.resolutionY;
      return same ? ONI_STATUS_OK : ONI_STATUS_NOT_SUPPORTED;
    }
    if (id == ONI_STREAM_PROPERTY_MIRRORING && size == sizeof(OniBool))
      return *static_cast<const OniBool*>(data) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    if (id == ONI_STREAM_PROPERTY_CROPPING && size == sizeof(OniCropping))
      return static_cast<const OniCropping*>(data)->enabled ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    return ONI_STATUS_NOT_SUPPORTED;
  }

  int getRequiredFrameSize() override { return stride_bytes() * scene::kHeight; }

 private:
  bool registered() const { return registration_ == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR; }
  int stride_bytes() const { return scene::kWidth * (type_ == ONI_SENSOR_DEPTH ? 2 : 3); }

  void produce() {
    const auto period = std::chrono::microseconds(1000000 / mode_.fps);
    const auto start = std::chrono::steady_clock::now();
    auto next = start;
    for (int index = 1; running_; ++index) {
      next += period;
      std::this_thread::sleep_until(next);
      OniFrame* frame = getServices().acquireFrame();
      if (frame == nullptr) continue;
      if (type_ == ONI_SENSOR_DEPTH)
        scene::render_depth(index, registered(), static_cast<uint16_t*>(frame->data), scene::kWidth);
      else scene::render_rgb(index, static_cast<uint8_t*>(frame->data), stride_bytes());
      frame->dataSize = getRequiredFrameSize();
      frame->sensorType = type_;
      frame->frameIndex = index;
      frame->timestamp = static_cast<uint64_t>(
          std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count());
      frame->videoMode = mode_;
      frame->width = scene::kWidth;
      frame->height = scene::kHeight;
      frame->croppingEnabled = FALSE;
      frame->cropOriginX = frame->cropOriginY = 0;
      frame->stride = stride_bytes();
      raiseNewFrame(frame);
      getServices().releaseFrame(frame);
    }
  }

  const OniSensorType type_;
  const std::atomic<int>& registration_;
  OniVideoMode mode_{};
  std::atomic<bool> running_{false};
  std::thread thread_;
};

class SynthDevice : public DeviceBase {
 public:
  SynthDevice() : fps_(frames_per_second()) {
    modes_[0] = {ONI_PIXEL_FORMAT_DEPTH_1_MM, scene::kWidth, scene::kHeight, fps_};
    modes_[1] = {ONI_PIXEL_FORMAT_RGB888, scene::kWidth, scene::kHeight, fps_};
    sensors_[0] = {ONI_SENSOR_DEPTH, 1, &modes_[0]};
    sensors_[1] = {ONI_SENSOR_COLOR, 1, &modes_[1]};
  }

  OniStatus getSensorInfoList(OniSensorInfo** sensors, int* count) override {
    *sensors = sensors_;
    *count = 2;
    return ONI_STATUS_OK;
  }

  StreamBase* createStream(OniSensorType type) override {
    if (type != ONI_SENSOR_DEPTH && type != ONI_SENSOR_COLOR) return nullptr;
    return new SynthStream(type, registration_, fps_);
  }

  void destroyStream(StreamBase* stream) override { delete stream; }

  OniBool isPropertySupported(int id) override { return id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION; }

  OniStatus getProperty(int id, void* data, int* size) override {
    if (id != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) return ONI_STATUS_NOT_SUPPORTED;
    return put(static_cast<OniImageRegistrationMode>(registration_.load()), data, size);
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    if (id != ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || size != sizeof(OniImageRegistrationMode))
      return ONI_STATUS_NOT_SUPPORTED;
    const auto mode = *static_cast<const OniImageRegistrationMode*>(data);
    if (!isImageRegistrationModeSupported(mode)) return ONI_STATUS_NOT_SUPPORTED;
    registration_ = mode;
    return ONI_STATUS_OK;
  }

  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode mode) override {
    return mode == ONI_IMAGE_REGISTRATION_OFF || mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR;
  }

 private:
  const int fps_;
  OniVideoMode modes_[2];
  OniSensorInfo sensors_[2];
  std::atomic<int> registration_{ONI_IMAGE_REGISTRATION_OFF};
};

class SynthDriver : public DriverBase {
 public:
  explicit SynthDriver(OniDriverServices* services) : DriverBase(services) {}

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed, void* cookie) override {
    DriverBase::initialize(connected, disconnected, state_changed, cookie);
    std::memset(&info_, 0, sizeof(info_));
    std::strncpy(info_.uri, kDeviceUri, ONI_MAX_STR - 1);
    std::strncpy(info_.vendor, "IVOA", ONI_MAX_STR - 1);
    std::strncpy(info_.name, "Synthetic depth sensor", ONI_MAX_STR - 1);
    deviceConnected(&info_);
    return ONI_STATUS_OK;
  }

  DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    if (uri == nullptr || std::strcmp(uri, kDeviceUri) != 0) return nullptr;
    return new SynthDevice();
  }

  void deviceClose(DeviceBase* device) override { delete device; }

  OniStatus tryDevice(const char* uri) override {
    return uri != nullptr && std::strcmp(uri, kDeviceUri) == 0 ? ONI_STATUS_OK : ONI_STATUS_ERROR;
  }

  void shutdown() override {}

 private:
  OniDeviceInfo info_{};
};

}  // namespace

ONI_EXPORT_DRIVER(SynthDriver)
