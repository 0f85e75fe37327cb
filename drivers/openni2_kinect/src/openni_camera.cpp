#include "ivoa/openni2_kinect/openni_camera.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <OpenNI.h>
#include <spdlog/spdlog.h>

#include "ivoa/core/file_names.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/openni2_kinect/frame_buffer.hpp"

namespace ivoa::openni2_kinect {
namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr int kFps = 30;
constexpr int kEndOfFileSilenceMs = 1000;  // a playing recording that delivers nothing for this long has ended
constexpr int kMaxRecordingSuffix = 999;   // kinect-1.oni ... kinect-999.oni

const char* const kNoDeviceHelp =
    "Is the sensor plugged in and powered (a Kinect v1 needs its mains adapter)? Debian's OpenNI2 drives only "
    "PrimeSense/Asus sensors: a Kinect v1 (045e:02ae) needs libfreenect's OpenNI2 driver (libFreenectDriver.so, "
    "built from libfreenect with -DBUILD_OPENNI2_DRIVER=ON and copied into "
    "/usr/lib/x86_64-linux-gnu/OpenNI2/Drivers/), and USB access for your user (udev rule)";

// OpenNI2's last error, on one line.
std::string extended_error() {
  std::string text = openni::OpenNI::getExtendedError();
  for (char& c : text)
    if (c == '\n' || c == '\t') c = ' ';
  const auto first = text.find_first_not_of(' ');
  if (first == std::string::npos) return "no details from OpenNI2";
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

// Prefers width x height in `format`, at the nominal rate if offered.
bool pick_mode(const openni::SensorInfo* info, openni::PixelFormat format, openni::VideoMode* out) {
  if (info == nullptr) return false;
  const auto& modes = info->getSupportedVideoModes();
  bool found = false;
  for (int i = 0; i < modes.getSize(); ++i) {
    const openni::VideoMode& m = modes[i];
    if (m.getResolutionX() != kWidth || m.getResolutionY() != kHeight || m.getPixelFormat() != format) continue;
    if (!found || m.getFps() == kFps) *out = m;
    found = true;
  }
  return found;
}

// Creates the recording's file and returns its name: `path`, or if that
// exists `stem-1.ext`, `stem-2.ext`, ... OpenNI2's recorder would truncate
// an existing file, and a driver respawned with the same name would erase
// the session it recorded before; refusing instead would stop the depth
// stream the rest of the system needs.
std::string claim_record_file(const std::string& path) {
  const auto name = first_free_numbered_name(path, kMaxRecordingSuffix, [](const std::string& candidate) {
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return true;
    }
    if (errno == EEXIST) return false;
    throw DeviceError(candidate + ": cannot record: " + std::strerror(errno), kExitIoError);
  });
  if (!name)
    throw DeviceError(path + ": cannot record: it and " + std::to_string(kMaxRecordingSuffix) +
                          " numbered variants exist (name recordings with a time pattern such as "
                          "kinect-%Y%m%d-%H%M%S.oni)",
                      kExitIoError);
  if (*name != path) spdlog::warn("{} exists (a recording is never overwritten): recording to {}", path, *name);
  return *name;
}

// Set on the OniFile player's thread when a recording that does not loop
// has played to its end: from then on that thread delivers no frames.
struct EndOfFileListener : openni::OpenNI::DeviceStateChangedListener {
  std::atomic<bool> reached{false};
  void onDeviceStateChanged(const openni::DeviceInfo*, openni::DeviceState state) override {
    if (state == openni::DEVICE_STATE_EOF) reached = true;
  }
};

// A frame whose data does not hold the image it claims is skipped, not
// wrapped (a damaged recording's mode read past the buffer's end).
void check_buffer(const openni::VideoFrameRef& frame, int bytes_per_pixel, const char* stream) {
  const std::string error = frame_buffer_error(frame.getWidth(), frame.getHeight(), frame.getStrideInBytes(),
                                               bytes_per_pixel, frame.getDataSize());
  if (!error.empty())
    throw BadFrame(std::string(stream) + " frame " + std::to_string(frame.getFrameIndex()) + ": " + error +
                   ": skipped");
}

}  // namespace

struct OpenNiCamera::Impl {
  OpenNiOptions options;
  bool file = false;
  bool initialized = false;
  bool registered = false;
  int frames_in_file = 0;
  int depth_frames_read = 0;
  int idle_ms = 0;  // waited without a frame
  openni::Device device;
  openni::VideoStream depth;
  openni::VideoStream color;
  openni::Recorder recorder;
  std::string description;
  EndOfFileListener end_of_file;
  bool listening = false;

  void open_device() {
    file = is_recording_path(options.device);
    if (file && !std::filesystem::is_regular_file(options.device))
      throw DeviceError(options.device + ": recording not found", kExitBadInput);
    if (openni::OpenNI::initialize() != openni::STATUS_OK)
      throw DeviceError("OpenNI2 does not initialise (are its drivers installed?): " + extended_error(), kExitFailure);
    initialized = true;
    if (file) listening = openni::OpenNI::addDeviceStateChangedListener(&end_of_file) == openni::STATUS_OK;
    const bool any = options.device.empty() || options.device == "ANY_DEVICE";
    if (any) {
      openni::Array<openni::DeviceInfo> devices;
      openni::OpenNI::enumerateDevices(&devices);
      if (devices.getSize() == 0)
        throw DeviceError(std::string("no OpenNI2 device found. ") + kNoDeviceHelp, kExitFailure);
    }
    if (device.open(any ? openni::ANY_DEVICE : options.device.c_str()) != openni::STATUS_OK) {
      if (file)
        throw DeviceError(options.device + ": not a playable .oni recording: " + extended_error(), kExitBadInput);
      throw DeviceError(
          "cannot open OpenNI2 device '" + options.device + "': " + extended_error() + ". " + kNoDeviceHelp,
          kExitFailure);
    }
    const openni::DeviceInfo& info = device.getDeviceInfo();
    description = std::string(info.getVendor()) + " " + info.getName() + " (" + info.getUri() + ")";
  }

  void create_stream(openni::VideoStream& stream, openni::SensorType sensor, openni::PixelFormat format,
                     const char* what) {
    if (stream.create(device, sensor) != openni::STATUS_OK)
      throw DeviceError(description + " has no " + what + " stream: " + extended_error(), kExitFailure);
    if (file) return;  // a recording plays the modes it was made with
    openni::VideoMode mode;
    if (!pick_mode(device.getSensorInfo(sensor), format, &mode) || stream.setVideoMode(mode) != openni::STATUS_OK)
      spdlog::warn("{}: no {}x{} {} mode; using the device's default", description, kWidth, kHeight, what);
    stream.setMirroringEnabled(false);  // geometry needs the unmirrored image
  }

  void set_registration() {
    if (!options.register_depth) return;
    if (file) {
      spdlog::warn(
          "{}: --register has no effect on a recording: its depth plays as recorded, published with the depth "
          "camera's intrinsics (give --rig with the colour camera's as K_depth if it was recorded registered)",
          options.device);
      return;
    }
    if (!device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR))
      throw DeviceError(description + " does not support depth-to-colour registration (--register)", kExitUsage);
    if (device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) != openni::STATUS_OK)
      throw DeviceError(description + ": cannot turn on registration: " + extended_error(), kExitFailure);
    registered = true;
  }

  // A depth mode or field of view no sensor has (a recording's damaged
  // header) is refused before any stream starts: the driver read past frames
  // (SIGSEGV) or aborted on them, and OpenNI2 could crash tearing down a
  // file player it had just started.
  void check_depth_stream() const {
    const openni::VideoMode mode = depth.getVideoMode();
    const int w = mode.getResolutionX(), h = mode.getResolutionY();
    if (w <= 0 || h <= 0 || int64_t{w} * h > kMaxImagePixels)
      throw DeviceError(description + ": its depth stream's mode is " + std::to_string(w) + "x" + std::to_string(h) +
                            ", no image size",
                        kExitBadInput);
    const double hfov = depth.getHorizontalFieldOfView(), vfov = depth.getVerticalFieldOfView();
    if (!(hfov > 0 && vfov > 0)) return;  // none reported: the nominal one is used
    try {
      intrinsics_from_fov(w, h, hfov, vfov);
    } catch (const std::invalid_argument& e) {
      throw DeviceError(
          description + ": its depth field of view: " + e.what() + " (give the sensor's calibration with --rig)",
          kExitBadInput);
    }
  }

  void start_streams() {
    if (depth.start() != openni::STATUS_OK)
      throw DeviceError(description + ": depth stream does not start: " + extended_error(), kExitFailure);
    if (color.isValid() && color.start() != openni::STATUS_OK)
      throw DeviceError(description + ": colour stream does not start: " + extended_error(), kExitFailure);
    if (color.isValid() && !file && device.setDepthColorSyncEnabled(true) != openni::STATUS_OK)
      spdlog::info("{}: depth/colour frame sync not available", description);
  }

  void set_up_playback() {
    if (!file) return;
    openni::PlaybackControl* playback = device.getPlaybackControl();
    if (playback == nullptr) return;
    playback->setSpeed(options.playback_speed > 0 ? static_cast<float>(options.playback_speed) : -1.0f);
    playback->setRepeatEnabled(options.loop);
    frames_in_file = playback->getNumberOfFrames(depth);
  }

  void start_recording() {
    if (options.record_path.empty()) return;
    options.record_path = claim_record_file(options.record_path);
    if (recorder.create(options.record_path.c_str()) != openni::STATUS_OK ||
        recorder.attach(depth, false) != openni::STATUS_OK ||
        (color.isValid() && recorder.attach(color, options.lossy_color) != openni::STATUS_OK) ||
        recorder.start() != openni::STATUS_OK) {
      const std::string why = extended_error();
      if (recorder.isValid()) recorder.destroy();
      std::error_code ignored;
      std::filesystem::remove(options.record_path, ignored);  // our empty claim, nothing recorded
      throw DeviceError(options.record_path + ": cannot record: " + why, kExitIoError);
    }
    spdlog::info("recording to {}", options.record_path);
  }

  // Streams stop before the recorder: OpenNI2 deadlocks if a frame is
  // delivered while a recorder is stopped. A recording played to its end
  // closes its device before its streams are destroyed: the OniFile player
  // thread, idle at the end, still walks its stream list without a lock, and
  // destroying a stream under it crashed about one exit in twenty on a loaded
  // host. Closing the device joins that thread first (OpenNI2 then leaves
  // the driver's stream objects alone). Stopped while playing, the usual
  // order is kept: closing first crashed there instead, in frame delivery.
  void close() {
    if (depth.isValid()) depth.stop();
    if (color.isValid()) color.stop();
    if (recorder.isValid()) {
      recorder.stop();
      recorder.destroy();
    }
    if (end_of_file.reached && device.isValid()) {
      spdlog::debug("{}: played to its end; closing the device before its streams", options.device);
      device.close();
    }
    if (depth.isValid()) depth.destroy();
    if (color.isValid()) color.destroy();
    if (device.isValid()) device.close();
    if (listening) openni::OpenNI::removeDeviceStateChangedListener(&end_of_file);
    listening = false;
    if (initialized) openni::OpenNI::shutdown();
    initialized = false;
  }
};

bool is_recording_path(const std::string& device) {
  const std::filesystem::path path(device);
  return path.extension() == ".oni" || std::filesystem::is_regular_file(path);
}

OpenNiCamera::OpenNiCamera(const OpenNiOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  try {
    m.open_device();
    m.create_stream(m.depth, openni::SENSOR_DEPTH, openni::PIXEL_FORMAT_DEPTH_1_MM, "depth");
    if (options.color) m.create_stream(m.color, openni::SENSOR_COLOR, openni::PIXEL_FORMAT_RGB888, "colour");
    m.set_registration();
    m.check_depth_stream();  // after registration, which gives depth the colour camera's view
    m.start_streams();
    m.set_up_playback();
    m.start_recording();
  } catch (const DeviceError& e) {
    // A damaged recording: OpenNI2 crashed now and then (SIGSEGV) tearing
    // down the file player it had just started, so it is left to the exit.
    if (e.exit_code() != kExitBadInput || !m.file) m.close();
    throw;
  } catch (...) {
    m.close();
    throw;
  }
}

OpenNiCamera::~OpenNiCamera() { impl_->close(); }

OpenNiCamera::Ready OpenNiCamera::wait(int timeout_ms) {
  Impl& m = *impl_;
  if (m.file && !m.options.loop && m.frames_in_file > 0 && m.depth_frames_read >= m.frames_in_file)
    return Ready::kEndOfRecording;
  openni::VideoStream* streams[2] = {&m.depth, &m.color};
  const int count = m.color.isValid() ? 2 : 1;
  int ready = -1;
  if (openni::OpenNI::waitForAnyStream(streams, count, &ready, timeout_ms) == openni::STATUS_OK) {
    m.idle_ms = 0;
    return ready == 0 ? Ready::kDepth : Ready::kColor;
  }
  // A frame the host was too slow to read is replaced by the next, so fewer
  // than the file's frames may be read: silence after playing also ends it.
  m.idle_ms += timeout_ms;
  if (m.file && !m.options.loop && m.depth_frames_read > 0 && m.idle_ms >= kEndOfFileSilenceMs)
    return Ready::kEndOfRecording;
  return Ready::kTimeout;
}

DepthFrame OpenNiCamera::read_depth() {
  openni::VideoFrameRef frame;
  if (impl_->depth.readFrame(&frame) != openni::STATUS_OK || !frame.isValid())
    throw DeviceError("depth frame cannot be read: " + extended_error(), kExitFailure);
  ++impl_->depth_frames_read;
  const openni::PixelFormat format = frame.getVideoMode().getPixelFormat();
  check_buffer(frame, 2, "depth");
  const cv::Mat wrapped(frame.getHeight(), frame.getWidth(), CV_16UC1, const_cast<void*>(frame.getData()),
                        static_cast<size_t>(frame.getStrideInBytes()));
  DepthFrame out;
  if (format == openni::PIXEL_FORMAT_DEPTH_1_MM) out.depth_mm = wrapped.clone();
  else if (format == openni::PIXEL_FORMAT_DEPTH_100_UM) wrapped.convertTo(out.depth_mm, CV_16U, 0.1);
  else
    throw DeviceError("depth stream delivers pixel format " + std::to_string(format) + ", not millimetres",
                      kExitFailure);
  out.frame_index = frame.getFrameIndex();
  out.device_time_us = frame.getTimestamp();
  return out;
}

ColorFrame OpenNiCamera::read_color() {
  openni::VideoFrameRef frame;
  if (impl_->color.readFrame(&frame) != openni::STATUS_OK || !frame.isValid())
    throw DeviceError("colour frame cannot be read: " + extended_error(), kExitFailure);
  if (frame.getVideoMode().getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
    throw DeviceError("colour stream is not RGB888", kExitFailure);
  check_buffer(frame, 3, "colour");
  const cv::Mat wrapped(frame.getHeight(), frame.getWidth(), CV_8UC3, const_cast<void*>(frame.getData()),
                        static_cast<size_t>(frame.getStrideInBytes()));
  ColorFrame out;
  out.rgb = wrapped.clone();
  out.frame_index = frame.getFrameIndex();
  out.device_time_us = frame.getTimestamp();
  return out;
}

bool OpenNiCamera::depth_fov_intrinsics(PinholeIntrinsics* out) const {
  const double hfov = impl_->depth.getHorizontalFieldOfView();
  const double vfov = impl_->depth.getVerticalFieldOfView();
  if (!(hfov > 0 && vfov > 0)) return false;
  *out = intrinsics_from_fov(depth_width(), depth_height(), hfov, vfov);
  return true;
}

int OpenNiCamera::depth_width() const { return impl_->depth.getVideoMode().getResolutionX(); }
int OpenNiCamera::depth_height() const { return impl_->depth.getVideoMode().getResolutionY(); }
bool OpenNiCamera::registered() const { return impl_->registered; }
std::string OpenNiCamera::description() const { return impl_->description; }
std::string OpenNiCamera::record_path() const { return impl_->recorder.isValid() ? impl_->options.record_path : ""; }

}  // namespace ivoa::openni2_kinect
