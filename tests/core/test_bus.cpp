// The LCM layer in process: memq:// publish/subscribe, decode errors routed
// to a handler, and file:// logs written and replayed through the same code.
#include <gtest/gtest.h>

#include <algorithm>
#include <exception>
#include <vector>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/image_convert.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

// Bounded retry instead of sleeps: handle until `done` or `tries` run out.
template <class Pred>
bool handle_until(Bus& bus, Pred done, int tries = 50) {
  for (int i = 0; i < tries && !done(); ++i) bus.handle(20);
  return done();
}

TEST(Bus, UdpmUrlsGetALargeReceiveBuffer) {
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667?ttl=0"),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=16777216");
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667"), "udpm://239.255.76.67:7667?recv_buf_size=16777216");
  EXPECT_EQ(with_receive_buffer("udpm://a:1?recv_buf_size=5"), "udpm://a:1?recv_buf_size=5");
  EXPECT_EQ(with_receive_buffer("memq://"), "memq://");
  // Given explicitly (--lcm-url), as from $LCM_DEFAULT_URL.
  EXPECT_EQ(effective_lcm_url("udpm://239.255.76.67:7689?ttl=0"),
            "udpm://239.255.76.67:7689?ttl=0&recv_buf_size=16777216");
  EXPECT_EQ(effective_lcm_url("memq://"), "memq://");
  EXPECT_EQ(Bus("memq://").url(), "memq://");
}

TEST(Bus, MemqPublishSubscribeSetsCounts) {
  Bus bus("memq://");
  int received = 0;
  stereo_image_t got;
  bus.subscribe<stereo_image_t>("BUS_TEST_STEREO", [&](const stereo_image_t& m, const ReceiveInfo& info) {
    got = m;
    EXPECT_EQ(info.channel, "BUS_TEST_STEREO");
    ++received;
  });
  stereo_image_t msg;
  msg.utime = 77;
  msg.seq = 3;
  msg.left = encode_image(cv::Mat(600, 960, CV_8UC3, cv::Scalar(1, 2, 3)), image_t::PIXEL_FORMAT_BGR, 77);
  msg.right = msg.left;
  msg.left.size = 0;  // a wrong count must be corrected by publish, not trusted
  ASSERT_TRUE(bus.publish("BUS_TEST_STEREO", msg));
  ASSERT_TRUE(handle_until(bus, [&] { return received == 1; }));
  EXPECT_EQ(got.seq, 3);
  EXPECT_EQ(got.left.size, 960 * 600 * 3);
}

TEST(Bus, UndecodableMessagesGoToTheErrorHandler) {
  Bus bus("memq://");
  int good = 0;
  std::vector<std::string> errors;
  bus.on_decode_error([&](const std::string& what) { errors.push_back(what); });
  bus.subscribe<depth_image_t>("BUS_TEST_DEPTH", [&](const depth_image_t&, const ReceiveInfo&) { ++good; });
  stereo_image_t wrong;
  bus.publish("BUS_TEST_DEPTH", wrong);
  const uint8_t garbage[5] = {1, 2, 3, 4, 5};
  bus.publish_raw("BUS_TEST_DEPTH", garbage, sizeof(garbage));
  ASSERT_TRUE(handle_until(bus, [&] { return errors.size() == 2; }));
  EXPECT_EQ(good, 0);
  EXPECT_NE(errors[0].find("BUS_TEST_DEPTH"), std::string::npos);
  EXPECT_NE(errors[0].find("ivoa.depth_image_t"), std::string::npos);
}

TEST(Bus, AMessageDamagedInsideIsAnErrorAndTheNextOneArrives) {
  Bus bus("memq://");
  std::vector<int64_t> got;
  std::vector<std::string> errors;
  bus.on_decode_error([&](const std::string& what) { errors.push_back(what); });
  bus.subscribe<stereo_image_t>("BUS_TEST_DAMAGED",
                                [&](const stereo_image_t& m, const ReceiveInfo&) { got.push_back(m.seq); });
  stereo_image_t msg{};
  msg.seq = 1;
  msg.source = "left";
  set_counts(msg);
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  ASSERT_GT(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  // fingerprint (8 bytes), utime, seq, then the source string's length: 0
  // makes lcm-gen's decode throw (std::length_error) instead of failing
  const size_t source_length_at = 24;
  std::fill_n(bytes.begin() + source_length_at, 4, uint8_t{0});
  stereo_image_t probe;
  EXPECT_THROW(probe.decode(bytes.data(), 0, static_cast<int>(bytes.size())), std::exception);
  ASSERT_TRUE(bus.publish_raw("BUS_TEST_DAMAGED", bytes.data(), bytes.size()));
  msg.seq = 2;
  ASSERT_TRUE(bus.publish("BUS_TEST_DAMAGED", msg));
  ASSERT_TRUE(handle_until(bus, [&] { return got.size() == 1; }));
  EXPECT_EQ(got, std::vector<int64_t>{2});
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("does not decode as ivoa.stereo_image_t: truncated or damaged inside"), std::string::npos)
      << errors[0];
}

// The fingerprint says which it was: another type on the channel, or a
// payload of no ivoa type.
TEST(Bus, AnUndecodableMessageIsSaidToBeAnotherTypeOrDamaged) {
  depth_image_t depth{};
  set_counts(depth);
  std::vector<uint8_t> bytes(static_cast<size_t>(depth.getEncodedSize()));
  ASSERT_GT(depth.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  EXPECT_EQ(Bus::decode_error_text("STEREO_IMAGES", "ivoa.stereo_image_t", bytes.data(), bytes.size()),
            "channel STEREO_IMAGES: " + std::to_string(bytes.size()) +
                "-byte message does not decode as ivoa.stereo_image_t: it is an ivoa.depth_image_t (another type on "
                "this channel)");
  bytes[0] ^= 0xff;
  EXPECT_NE(Bus::decode_error_text("STEREO_IMAGES", "ivoa.stereo_image_t", bytes.data(), bytes.size())
                .find("an unknown type's fingerprint"),
            std::string::npos);
}

TEST(Bus, LogWrittenAndReplayedThroughTheSameInterface) {
  test::TempDir dir;
  const std::string log = dir.file("test.lcmlog");
  {
    Bus writer("file://" + log + "?mode=w");
    for (int i = 0; i < 5; ++i) {
      process_status_t s;
      s.utime = i;
      s.name = "writer";
      writer.publish("BUS_TEST_STATUS", s);
    }
  }
  Bus reader("file://" + log + "?speed=0");
  std::vector<int64_t> utimes;
  reader.subscribe<process_status_t>("BUS_TEST_STATUS",
                                     [&](const process_status_t& s, const ReceiveInfo&) { utimes.push_back(s.utime); });
  while (reader.handle(100) >= 0) {
  }
  EXPECT_EQ(utimes, (std::vector<int64_t>{0, 1, 2, 3, 4}));
}

// lcm::LCM::subscribe hands back a subscription even for a regex GLib
// cannot compile, which crashed `ivoa-lcm-stats --channels '['`.
TEST(Bus, ChannelRegexThatDoesNotCompileThrowsWithTheRegex) {
  Bus bus("memq://");
  try {
    bus.subscribe_raw("CAMERA[", [](const void*, size_t, const ReceiveInfo&) {});
    FAIL() << "subscribed with a regex that does not compile";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("'CAMERA['"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a valid channel regex"), std::string::npos) << e.what();
  }
  int received = 0;
  bus.subscribe_raw("BUS_TEST_RE.*", [&](const void*, size_t, const ReceiveInfo&) { ++received; });
  const char byte = 1;
  ASSERT_TRUE(bus.publish_raw("BUS_TEST_REGEX", &byte, 1));
  EXPECT_TRUE(handle_until(bus, [&] { return received == 1; })) << "the bus still works after the refusal";
}

TEST(Bus, BadUrlThrowsWithTheUrl) {
  try {
    Bus bus("nonsense://x");
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("nonsense://x"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("LCM URLs: udpm://"), std::string::npos) << e.what();
    EXPECT_EQ(e.exit_code(), kExitUsage);
  }
}

// A log to replay that is not there is an unusable input file (exit 3),
// said as such: not a hint about multicast routes.
TEST(Bus, MissingLogToReplayIsBadInputNamingTheFile) {
  try {
    Bus bus("file:///nonexistent/bus_test/session.lcmlog?speed=0");
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("the log '/nonexistent/bus_test/session.lcmlog' does not exist"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find("multicast"), std::string::npos) << e.what();
    EXPECT_EQ(e.exit_code(), kExitBadInput);
  }
  try {
    Bus bus("file:///nonexistent/bus_test/out.lcmlog?mode=w");
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("its folder /nonexistent/bus_test does not exist"), std::string::npos)
        << e.what();
    EXPECT_EQ(e.exit_code(), kExitIoError);
  }
  try {
    Bus bus("file:///tmp?mode=w");
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("'/tmp' is a folder, not a log file"), std::string::npos) << e.what();
  }
}

// A group that is no multicast address is a usage error, not a routing one.
TEST(Bus, AGroupThatIsNoMulticastAddressIsNamed) {
  for (const char* group : {"999.1.1.1", "10.0.0.1"}) {
    try {
      Bus bus(std::string("udpm://") + group + ":7667?ttl=0");
      FAIL() << group;
    } catch (const BusError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + group + "' is not a multicast group"), std::string::npos)
          << e.what();
      EXPECT_EQ(e.exit_code(), kExitUsage);
    }
  }
}

// 99999 was blamed on the multicast route; 0 failed at the first subscription, 10 s later.
TEST(Bus, APortLcmCannotUseIsNamed) {
  for (const char* port : {"99999", "0", "x"}) {
    try {
      Bus bus(std::string("udpm://239.255.76.67:") + port + "?ttl=0");
      FAIL() << port;
    } catch (const BusError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("port '") + port + "' is not 1 to 65535"), std::string::npos)
          << e.what();
      EXPECT_EQ(e.exit_code(), kExitUsage);
    }
  }
}

}  // namespace
}  // namespace ivoa
