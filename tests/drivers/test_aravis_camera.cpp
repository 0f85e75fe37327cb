// The driver's AravisCamera against a simulated GigE Vision camera on
// 127.0.0.1 (real GVCP/GVSP over loopback; run inside the test network
// namespace): real Aravis buffers through the driver's copy and
// conversions. GenICam BayerRG8 must come out with the right colours
// (cv::COLOR_BayerBG2BGR, not BayerRG2BGR), Mono8 as gray.
#include <gtest/gtest.h>

#include <condition_variable>
#include <mutex>

#include <opencv2/imgproc.hpp>

#include "ivoa/aravis_stereo/aravis_buffer.hpp"
#include "ivoa/aravis_stereo/aravis_camera.hpp"
#include "ivoa/aravis_stereo/stereo_message.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/image_t.hpp"
#include "ivoa/sim_hardware/fake_gige_camera.hpp"
#include "ivoa/sim_hardware/frame_stamp.hpp"

namespace ivoa::aravis_stereo {
namespace {

using sim_hardware::RigCamera;

// Collects complete frames from a camera; waits are bounded.
class FrameCollector {
 public:
  CameraSource::FrameCallback callback() {
    return [this](FrameResult&& r) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (r.complete) frames_.push_back(std::move(r.frame));
      else problems_.push_back(r.problem);
      arrived_.notify_all();
    };
  }
  bool wait_for(size_t n, std::chrono::seconds limit) {
    std::unique_lock<std::mutex> lock(mutex_);
    return arrived_.wait_for(lock, limit, [&] { return frames_.size() >= n; });
  }
  std::vector<CameraFrame> frames() {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<CameraFrame> frames_;
  std::vector<std::string> problems_;
};

cv::Mat as_mat(const CameraFrame& f) {
  return cv::Mat(f.height, f.width, CV_8UC1, const_cast<uint8_t*>(f.data.data())).clone();
}

double mean_abs_diff(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const cv::Scalar m = cv::mean(diff, mask);
  return (m[0] + m[1] + m[2]) / 3.0;
}

class AravisCameraTest : public ::testing::Test {
 protected:
  sim_hardware::StereoScene scene{sim_hardware::PatternOptions{}};
  std::unique_ptr<sim_hardware::FakeGigeCamera> fake;

  void SetUp() override {
    sim_hardware::FakeGigeCameraOptions options;
    options.address = "127.0.0.1";
    options.serial = "UNIT";
    fake = std::make_unique<sim_hardware::FakeGigeCamera>(scene, RigCamera::kLeft, options);
  }

  static AravisCameraConfig config(const char* pixel_format) {
    AravisCameraConfig c;
    c.device = "127.0.0.1";
    c.pixel_format = pixel_format;
    c.width = 320;
    c.height = 240;
    c.frame_rate_hz = 30;
    c.packet_size = 8192;
    return c;
  }

  // Three complete frames from a fresh driver-side camera.
  std::vector<CameraFrame> grab(const AravisCameraConfig& c) {
    AravisCamera camera(Side::kLeft, c);
    FrameCollector collector;
    camera.start(collector.callback());
    const bool arrived = collector.wait_for(3, std::chrono::seconds(10));
    camera.stop();
    EXPECT_TRUE(arrived) << "fewer than 3 complete frames in 10 s";
    return collector.frames();
  }
};

// A buffer the stream hands back unfilled is no frame and no lost frame:
// counting it as incomplete reported frames lost at every start.
TEST(AravisBuffer, AnUnfilledBufferIsNotAFrame) {
  ArvBuffer* buffer = arv_buffer_new_allocate(64);
  EXPECT_EQ(arv_buffer_get_status(buffer), ARV_BUFFER_STATUS_CLEARED);
  EXPECT_FALSE(buffer_was_filled(buffer));
  g_object_unref(buffer);
}

TEST_F(AravisCameraTest, BayerRG8FramesAreTheServedPixelsLabelledRGGB) {
  const auto frames = grab(config("BayerRG8"));
  ASSERT_GE(frames.size(), 3u);
  for (const CameraFrame& f : frames) {
    EXPECT_EQ(f.pixelformat, image_t::PIXEL_FORMAT_BAYER_RGGB);
    ASSERT_EQ(f.width, 320);
    ASSERT_EQ(f.height, 240);
    EXPECT_GT(f.utime, 1'500'000'000'000'000);  // host time, us since the epoch
    const cv::Mat raw = as_mat(f);
    const auto tick = sim_hardware::read_stamp(raw);
    ASSERT_TRUE(tick) << "no frame stamp in the raw Bayer image";
    const cv::Mat served =
        mosaic_bayer(scene.render(RigCamera::kLeft, *tick, {320, 240}), image_t::PIXEL_FORMAT_BAYER_RGGB);
    EXPECT_EQ(cv::norm(raw, served, cv::NORM_INF), 0.0);
  }
  EXPECT_NE(sim_hardware::read_stamp(as_mat(frames[0]))->tick, sim_hardware::read_stamp(as_mat(frames[2]))->tick);
}

TEST_F(AravisCameraTest, BayerRG8DemosaicsToTheSceneColours) {
  const auto frames = grab(config("BayerRG8"));
  ASSERT_FALSE(frames.empty());
  const cv::Mat bgr = decode_image(frame_to_image(frames[0], OutputFormat::kBgr));
  const auto tick = sim_hardware::read_stamp(bgr);
  ASSERT_TRUE(tick) << "the stamp does not survive demosaicing";
  const cv::Mat truth = scene.render(RigCamera::kLeft, {tick->tick, false}, bgr.size());
  const cv::Mat flat = scene.flat_colour_mask(RigCamera::kLeft, tick->tick, bgr.size());
  ASSERT_GT(cv::countNonZero(flat), 10'000);
  EXPECT_LT(mean_abs_diff(bgr, truth, flat), 1.0) << "colours inside the squares must be exact";

  // The classic mistake: OpenCV's BayerRG2BGR for GenICam BayerRG8 swaps red and blue.
  cv::Mat swapped;
  cv::cvtColor(as_mat(frames[0]), swapped, cv::COLOR_BayerRG2BGR);
  EXPECT_GT(mean_abs_diff(swapped, truth, flat), 40.0);
}

TEST_F(AravisCameraTest, Mono8IsGray) {
  const auto frames = grab(config("Mono8"));
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames[0].pixelformat, image_t::PIXEL_FORMAT_GRAY);
  const cv::Mat gray = as_mat(frames[0]);
  const auto tick = sim_hardware::read_stamp(gray);
  ASSERT_TRUE(tick);
  cv::Mat expected;
  cv::cvtColor(scene.render(RigCamera::kLeft, *tick, gray.size()), expected, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(gray, expected, cv::NORM_INF), 0.0);
}

TEST_F(AravisCameraTest, UnsupportedPixelFormatIsAConfigurationErrorListingTheOffers) {
  AravisCamera camera(Side::kRight, config("YUV422Packed"));
  try {
    camera.start([](FrameResult&&) {});
    FAIL() << "expected CameraConfigError";
  } catch (const CameraConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("YUV422Packed"), std::string::npos) << what;
    EXPECT_NE(what.find("BayerRG8"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace ivoa::aravis_stereo
