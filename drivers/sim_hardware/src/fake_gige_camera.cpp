#include "ivoa/sim_hardware/fake_gige_camera.hpp"

#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "ivoa/aravis_stereo/pixel_formats.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"

namespace ivoa::sim_hardware {
namespace {

// What a sensor with this pixel format records of a BGR scene; empty if
// the format is not an 8-bit one the fake can carry (its payload is
// width x height bytes whatever the format).
cv::Mat sensor_image(const cv::Mat& bgr, ArvPixelFormat format) {
  const auto ivoa_format = aravis_stereo::ivoa_pixelformat_from_genicam(format);
  if (!ivoa_format) return {};
  if (is_bayer(*ivoa_format)) return mosaic_bayer(bgr, *ivoa_format);
  if (*ivoa_format == image_t::PIXEL_FORMAT_GRAY) {
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    return gray;
  }
  return {};
}

}  // namespace

SceneFiller::SceneFiller(const StereoScene& scene, RigCamera camera, ArvFakeCamera* fake)
    : scene_(scene), camera_(camera), fake_(fake) {
  arv_fake_camera_set_fill_pattern(fake_, &SceneFiller::fill, this);
}

FrameStamp SceneFiller::stamp_of(ArvBuffer* buffer) {
  if (arv_fake_camera_is_in_software_trigger_mode(fake_))
    return {static_cast<uint32_t>(arv_buffer_get_frame_id(buffer)), false};
  guint32 period_us = 0;
  arv_fake_camera_read_register(fake_, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US, &period_us);
  if (period_us == 0) period_us = 40000;
  const uint64_t time_us = arv_buffer_get_timestamp(buffer) / 1000;
  // Frames fire on multiples of the period; round so a few ms late still counts.
  const uint64_t tick = (time_us + period_us / 2) / period_us;
  // A starved simulator thread fires late: more than a quarter period off
  // its slot, which instant the frame shows is ambiguous; say so.
  const int64_t off_us = static_cast<int64_t>(time_us) - static_cast<int64_t>(tick * period_us);
  const bool off_beat = std::llabs(off_us) > period_us / 4;
  if (off_beat) ++off_beat_;
  return {static_cast<uint32_t>(tick), off_beat};
}

// Runs on the fake camera's thread, under its fill mutex.
void SceneFiller::fill(ArvBuffer* buffer, void* self_ptr, guint32, guint32, ArvPixelFormat format) {
  auto* self = static_cast<SceneFiller*>(self_ptr);
  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  const cv::Mat raw = sensor_image(self->scene_.render(self->camera_, self->stamp_of(buffer), {width, height}), format);
  if (raw.empty()) {
    if (!self->warned_format_.exchange(true))
      spdlog::warn("{} fake camera: pixel format 0x{:08x} is not served (8-bit Bayer or Mono8 only)",
                   rig_camera_name(self->camera_), format);
    return;
  }
  // Inside the callback Aravis reports a data size of 0; the buffer holds
  // width x height bytes (the fake's payload).
  size_t ignored = 0;
  auto* data = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
  for (int y = 0; y < height; ++y) std::memcpy(data + static_cast<size_t>(y) * width, raw.ptr(y), width);
  ++self->frames_;
}

FakeGigeCamera::FakeGigeCamera(const StereoScene& scene, RigCamera camera, const FakeGigeCameraOptions& options) {
  gv_ = arv_gv_fake_camera_new_full(options.address.c_str(), options.serial.c_str(),
                                    options.genicam_xml.empty() ? nullptr : options.genicam_xml.c_str());
  if (gv_ == nullptr || !arv_gv_fake_camera_is_running(gv_)) {
    if (gv_ != nullptr) g_object_unref(gv_);
    throw std::runtime_error(std::string(rig_camera_name(camera)) + " fake camera cannot serve on " + options.address +
                             " (is the address on an interface? is port 3956 free?)");
  }
  if (options.packet_loss > 0) g_object_set(gv_, "gvsp-lost-ratio", options.packet_loss, nullptr);
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(gv_);
  arv_fake_camera_set_trigger_frequency(fake, options.trigger_poll_hz);
  filler_ = std::make_unique<SceneFiller>(scene, camera, fake);
}

FakeGigeCamera::~FakeGigeCamera() {
  g_object_unref(gv_);  // stops and joins the camera's thread first
  filler_.reset();
}

}  // namespace ivoa::sim_hardware
