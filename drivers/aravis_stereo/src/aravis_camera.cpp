#include "ivoa/aravis_stereo/aravis_camera.hpp"

#include <atomic>
#include <list>
#include <mutex>
#include <regex>
#include <thread>

#include <spdlog/spdlog.h>

#include "ivoa/aravis_stereo/aravis_buffer.hpp"
#include "ivoa/aravis_stereo/pixel_formats.hpp"

namespace ivoa::aravis_stereo {
namespace {

// Aravis' device list is global; discovery from two camera threads at once
// would race.
std::mutex g_discovery_mutex;

// Takes ownership of a GError and returns its message ("" if none).
std::string take_error(GError*& error) {
  if (error == nullptr) return {};
  std::string message = error->message;
  g_clear_error(&error);
  return message;
}

bool is_ipv4_address(const std::string& text) {
  static const std::regex ipv4(R"(^\d{1,3}\.\d{1,3}\.\d{1,3}\.\d{1,3}$)");
  return std::regex_match(text, ipv4);
}

std::string or_empty(const char* text) { return text ? text : ""; }

// What arv_camera_new should be given for `device`. An IP address is used
// as is: opening by address picks the host interface by subnet, which is
// deterministic (opening by id takes the first discovery reply, whichever
// interface it came through). An id, serial number or MAC is looked up by
// discovery (about 1 s) and, for GigE Vision, turned into its address.
std::string resolve_device(const std::string& device) {
  if (is_ipv4_address(device)) return device;
  std::lock_guard<std::mutex> lock(g_discovery_mutex);
  arv_update_device_list();
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    const std::string id = or_empty(arv_get_device_id(i));
    const bool match = device == id || device == or_empty(arv_get_device_serial_nbr(i)) ||
                       device == or_empty(arv_get_device_physical_id(i)) ||
                       device == or_empty(arv_get_device_address(i));
    if (!match) continue;
    const std::string address = or_empty(arv_get_device_address(i));
    if (or_empty(arv_get_device_protocol(i)) == "GigEVision" && !address.empty()) return address;
    return id;
  }
  return device;  // perhaps a user-defined name Aravis can still open
}

std::string available_pixel_formats(ArvCamera* camera) {
  guint n = 0;
  GError* error = nullptr;
  const char** names = arv_camera_dup_available_pixel_formats_as_strings(camera, &n, &error);
  take_error(error);
  std::string list;
  for (guint i = 0; names && i < n; ++i) list += (i ? ", " : "") + or_empty(names[i]);
  g_free(names);
  return list.empty() ? "unknown" : list;
}

}  // namespace

struct AravisCamera::Impl {
  Side side;
  AravisCameraConfig config;
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong new_buffer_handler = 0;
  gulong control_lost_handler = 0;
  std::atomic<bool> control_lost{false};
  FrameCallback on_frame;
  std::string description;

  std::string name() const { return std::string(side_name(side)) + " camera " + config.device; }

  // Runs `step` (an Aravis call taking GError**); a failure is a warning
  // naming the setting, since cameras differ in which features they have.
  template <class Step>
  bool optional_setting(const char* what, Step step) {
    GError* error = nullptr;
    step(&error);
    if (error == nullptr) return true;
    spdlog::warn("{}: cannot set {}: {} (keeping the camera's setting)", name(), what, take_error(error));
    return false;
  }

  template <class Step>
  void required_setting(const std::string& what, Step step) {
    GError* error = nullptr;
    step(&error);
    if (error != nullptr) throw CameraConfigError("cannot set " + what + ": " + take_error(error));
  }

  void open() {
    const std::string target = resolve_device(config.device);
    GError* error = nullptr;
    camera = arv_camera_new(target.c_str(), &error);
    if (camera == nullptr) throw CameraError("cannot connect to '" + target + "': " + take_error(error));
    description = name() + " (" + or_empty(arv_camera_get_vendor_name(camera, nullptr)) + " " +
                  or_empty(arv_camera_get_model_name(camera, nullptr)) + ", serial " +
                  or_empty(arv_camera_get_device_serial_number(camera, nullptr)) + ")";
    control_lost_handler =
        g_signal_connect(arv_camera_get_device(camera), "control-lost", G_CALLBACK(&Impl::on_control_lost), this);
  }

  void configure_transport() {
    if (!arv_camera_is_gv_device(camera)) return;
    if (config.packet_size > 0) {
      optional_setting("packet size",
                       [&](GError** e) { arv_camera_gv_set_packet_size(camera, config.packet_size, e); });
    } else {
      GError* error = nullptr;
      arv_camera_gv_auto_packet_size(camera, &error);
      if (error) spdlog::info("{}: automatic packet size not available: {}", name(), take_error(error));
    }
    if (config.packet_delay_ns > 0)
      optional_setting("packet delay",
                       [&](GError** e) { arv_camera_gv_set_packet_delay(camera, config.packet_delay_ns, e); });
    if (config.throughput_limit > 0)
      optional_setting("DeviceLinkThroughputLimit", [&](GError** e) {
        arv_camera_set_integer(camera, "DeviceLinkThroughputLimit", config.throughput_limit, e);
      });
  }

  void configure_image() {
    GError* ignored = nullptr;
    arv_camera_stop_acquisition(camera, &ignored);  // in case a previous client left it streaming
    take_error(ignored);
    GError* error = nullptr;
    arv_camera_set_pixel_format_from_string(camera, config.pixel_format.c_str(), &error);
    if (error != nullptr)
      throw CameraConfigError("pixel format '" + config.pixel_format + "' refused (" + take_error(error) +
                              "); the camera offers: " + available_pixel_formats(camera));
    const ArvPixelFormat format = arv_camera_get_pixel_format(camera, nullptr);
    if (!ivoa_pixelformat_from_genicam(format))
      throw CameraConfigError("pixel format '" + config.pixel_format + "' has no ivoa image_t equivalent; use one of " +
                              kMappedPixelFormats);
    if (config.width > 0 && config.height > 0)
      required_setting("region " + std::to_string(config.width) + "x" + std::to_string(config.height), [&](GError** e) {
        arv_camera_set_region(camera, config.offset_x, config.offset_y, config.width, config.height, e);
      });
  }

  void configure_acquisition() {
    if (config.trigger == "none") {
      GError* ignored = nullptr;
      arv_camera_clear_triggers(camera, &ignored);  // not every camera has trigger features
      take_error(ignored);
      if (config.frame_rate_hz > 0)
        optional_setting("frame rate", [&](GError** e) { arv_camera_set_frame_rate(camera, config.frame_rate_hz, e); });
    } else {
      const std::string source = config.trigger == "software" ? "Software" : config.trigger;
      required_setting("trigger source " + source,
                       [&](GError** e) { arv_camera_set_trigger(camera, source.c_str(), e); });
    }
    if (config.exposure_us > 0) {
      GError* ignored = nullptr;
      arv_camera_set_exposure_time_auto(camera, ARV_AUTO_OFF, &ignored);
      take_error(ignored);
      optional_setting("exposure time",
                       [&](GError** e) { arv_camera_set_exposure_time(camera, config.exposure_us, e); });
    } else {
      optional_setting("auto exposure",
                       [&](GError** e) { arv_camera_set_exposure_time_auto(camera, ARV_AUTO_CONTINUOUS, e); });
    }
    if (config.gain >= 0) {
      GError* ignored = nullptr;
      arv_camera_set_gain_auto(camera, ARV_AUTO_OFF, &ignored);
      take_error(ignored);
      optional_setting("gain", [&](GError** e) { arv_camera_set_gain(camera, config.gain, e); });
    } else {
      optional_setting("auto gain", [&](GError** e) { arv_camera_set_gain_auto(camera, ARV_AUTO_CONTINUOUS, e); });
    }
  }

  void create_stream() {
    GError* error = nullptr;
    stream = arv_camera_create_stream(camera, nullptr, nullptr, &error);
    if (stream == nullptr) throw CameraError(name() + ": cannot create a stream: " + take_error(error));
    if (ARV_IS_GV_STREAM(stream)) {
      // A socket buffer sized to the payload: with the kernel default about
      // 40 % of packets were lost under load (drivers_notes.md 1.a).
      g_object_set(stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, "socket-buffer-size", 0, "packet-resend",
                   config.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                   nullptr);
    }
    const guint payload = arv_camera_get_payload(camera, &error);
    if (error != nullptr) throw CameraError(name() + ": cannot read the payload size: " + take_error(error));
    // The handler first: buffers the stream thread hands back before it
    // emits signals would otherwise wait in the output queue unannounced.
    new_buffer_handler = g_signal_connect(stream, "new-buffer", G_CALLBACK(&Impl::on_new_buffer), this);
    arv_stream_set_emit_signals(stream, TRUE);
    for (int i = 0; i < config.buffers; ++i) arv_stream_push_buffer(stream, arv_buffer_new_allocate(payload));
  }

  void start_acquisition() {
    GError* error = nullptr;
    arv_camera_start_acquisition(camera, &error);
    if (error != nullptr) throw CameraError(name() + ": cannot start acquisition: " + take_error(error));
    gint x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera, &x, &y, &w, &h, nullptr);
    GError* ignored = nullptr;
    const double rate = arv_camera_get_frame_rate(camera, &ignored);
    take_error(ignored);
    const int packet =
        arv_camera_is_gv_device(camera) ? static_cast<int>(arv_camera_gv_get_packet_size(camera, nullptr)) : 0;
    spdlog::info("{}: streaming {}x{} {} at {:.1f} Hz, trigger {}, packet size {}", description, w, h,
                 or_empty(arv_camera_get_pixel_format_as_string(camera, nullptr)), rate, config.trigger, packet);
  }

  // Called on the stream's thread. Aravis allows pop/push from other threads.
  // Drains the output queue, not one buffer a signal: a buffer queued with
  // no signal behind it (Aravis 0.8 hands back unfilled ones as the stream
  // starts) would otherwise delay every later frame of this camera by one,
  // and a few of them leave no frame pairable with the other camera's.
  static void on_new_buffer(ArvStream* stream, gpointer self_ptr) {
    auto* self = static_cast<Impl*>(self_ptr);
    while (ArvBuffer* buffer = arv_stream_try_pop_buffer(stream)) {
      if (!buffer_was_filled(buffer)) {
        spdlog::debug("{}: a buffer handed back unfilled", self->description);
        arv_stream_push_buffer(stream, buffer);
        continue;
      }
      FrameResult result = buffer_to_frame(buffer, self->side);
      arv_stream_push_buffer(stream, buffer);
      if (self->on_frame) self->on_frame(std::move(result));
    }
  }

  static void on_control_lost(ArvDevice*, gpointer self_ptr) { static_cast<Impl*>(self_ptr)->control_lost = true; }

  // The Aravis objects of one connection, with our callbacks detached.
  struct Handles {
    ArvCamera* camera = nullptr;
    ArvStream* stream = nullptr;
    bool stop_acquisition = false;
  };

  Handles detach() {
    Handles h{camera, stream, camera != nullptr && !control_lost};
    if (stream != nullptr) {
      arv_stream_set_emit_signals(stream, FALSE);
      g_signal_handler_disconnect(stream, new_buffer_handler);
    }
    if (camera != nullptr) g_signal_handler_disconnect(arv_camera_get_device(camera), control_lost_handler);
    camera = nullptr;
    stream = nullptr;
    return h;
  }

  static void release(const Handles& h) {
    if (h.stop_acquisition) {
      GError* ignored = nullptr;
      arv_camera_stop_acquisition(h.camera, &ignored);
      take_error(ignored);
    }
    if (h.stream != nullptr) g_object_unref(h.stream);  // joins the stream thread
    if (h.camera != nullptr) g_object_unref(h.camera);
  }

  void close() {
    release(detach());
    on_frame = nullptr;
  }

  // Connections being released in the background, joined when done.
  struct Reaper {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done = std::make_shared<std::atomic<bool>>(false);
  };
  std::list<Reaper> reapers;

  void reap(Handles h) {
    for (auto it = reapers.begin(); it != reapers.end();) {
      if (*it->done) {
        it->thread.join();
        it = reapers.erase(it);
      } else {
        ++it;
      }
    }
    Reaper& r = reapers.emplace_back();
    r.thread = std::thread([h, done = r.done] {
      release(h);
      *done = true;
    });
  }

  void join_reapers() {
    for (Reaper& r : reapers) r.thread.join();
    reapers.clear();
  }
};

AravisCamera::AravisCamera(Side side, AravisCameraConfig config) : impl_(std::make_unique<Impl>()) {
  impl_->side = side;
  impl_->config = std::move(config);
}

AravisCamera::~AravisCamera() {
  stop();
  impl_->join_reapers();
}

void AravisCamera::start(FrameCallback on_frame) {
  stop();
  impl_->control_lost = false;
  impl_->on_frame = std::move(on_frame);
  try {
    impl_->open();
    impl_->configure_transport();
    impl_->configure_image();
    impl_->configure_acquisition();
    impl_->create_stream();
    impl_->start_acquisition();
  } catch (...) {
    impl_->close();
    throw;
  }
}

void AravisCamera::stop() { impl_->close(); }

void AravisCamera::abandon() {
  impl_->reap(impl_->detach());
  impl_->on_frame = nullptr;
}

void AravisCamera::software_trigger() {
  if (impl_->camera == nullptr) throw CameraError(impl_->name() + ": not open");
  GError* error = nullptr;
  arv_camera_software_trigger(impl_->camera, &error);
  if (error != nullptr) throw CameraError(take_error(error));
}

bool AravisCamera::control_lost() const { return impl_->control_lost; }

std::string AravisCamera::describe() const { return impl_->name(); }

}  // namespace ivoa::aravis_stereo
