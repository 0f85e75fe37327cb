// Message types: pinned fingerprints (old logs must keep decoding) and
// encode/decode round trips for every type, including a full-size stereo pair.
#include <fstream>
#include <limits>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/message_registry.hpp"

namespace ivoa {
namespace {

std::map<std::string, int64_t> read_expected() {
  std::ifstream in(IVOA_EXPECTED_FINGERPRINTS);
  std::map<std::string, int64_t> out;
  std::string name;
  int64_t fp;
  while (in >> name) {
    if (name[0] == '#') {
      std::getline(in, name);
      continue;
    }
    in >> fp;
    out[name] = fp;
  }
  return out;
}

TEST(Messages, FingerprintsArePinned) {
  // A changed fingerprint means logs recorded before the change no longer
  // decode. Add a new type instead of editing fields; if a change is truly
  // intended (no logs exist yet), update expected_fingerprints.txt.
  const auto expected = read_expected();
  ASSERT_FALSE(expected.empty()) << "cannot read " << IVOA_EXPECTED_FINGERPRINTS;
  for (const auto& type : message_types()) {
    const auto it = expected.find(std::string(type.name));
    ASSERT_NE(it, expected.end()) << type.name << " has no pinned fingerprint (add: " << type.name << " "
                                  << type.fingerprint << ")";
    EXPECT_EQ(it->second, type.fingerprint)
        << type.name << " changed its fingerprint: a field was renamed, retyped or reordered";
  }
  EXPECT_EQ(expected.size(), message_types().size()) << "a pinned type is no longer registered";
}

template <class Msg>
Msg round_trip(Msg& msg) {
  set_counts(msg);
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  Msg out;
  EXPECT_EQ(out.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(payload_type_name(buf.data(), buf.size()).value_or("?"), std::string("ivoa.") + Msg::getTypeName());
  return out;
}

image_t random_image(int w, int h, int channels, std::mt19937& rng) {
  image_t img;
  img.utime = 1700000000000000;
  img.width = w;
  img.height = h;
  img.row_stride = w * channels;
  img.pixelformat = channels == 3 ? int32_t{image_t::PIXEL_FORMAT_RGB} : int32_t{image_t::PIXEL_FORMAT_GRAY};
  img.data.resize(static_cast<size_t>(w * h * channels));
  for (auto& b : img.data) b = static_cast<uint8_t>(rng());
  return img;
}

TEST(Messages, FullSizeStereoPairRoundTrips) {
  std::mt19937 rng(1);
  stereo_image_t msg;
  msg.utime = 1700000000123456;
  msg.seq = 42;
  msg.source = "test";
  msg.left = random_image(960, 600, 3, rng);
  msg.right = random_image(960, 600, 3, rng);
  const stereo_image_t out = round_trip(msg);
  EXPECT_EQ(out.utime, msg.utime);
  EXPECT_EQ(out.seq, 42);
  EXPECT_EQ(out.left.size, 960 * 600 * 3);
  EXPECT_EQ(out.left.data, msg.left.data);
  EXPECT_EQ(out.right.data, msg.right.data);
}

TEST(Messages, DepthAndCalibrationRoundTrip) {
  depth_image_t depth;
  depth.utime = 5;
  depth.width = 4;
  depth.height = 2;
  depth.fx = 570.5;
  depth.format = depth_image_t::FORMAT_MM_U16LE;
  depth.data = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  const auto d = round_trip(depth);
  EXPECT_EQ(d.data, depth.data);
  EXPECT_DOUBLE_EQ(d.fx, 570.5);

  rig_calibration_t rig{};
  rig.utime = 7;
  rig.rig_name = "r";
  rig.left.K[0] = 600;
  rig.stereo_T[0] = -0.12;
  rig.depth_max_range = 4.5;
  const auto r = round_trip(rig);
  EXPECT_EQ(r.rig_name, "r");
  EXPECT_DOUBLE_EQ(r.left.K[0], 600);
  EXPECT_DOUBLE_EQ(r.stereo_T[0], -0.12);
}

TEST(Messages, GridLabelsIntrospectionStatusRoundTrip) {
  obstacle_grid_t grid{};
  grid.utime = 11;
  grid.detector = "jppc";
  grid.state = {0, 1, 2};
  grid.x = grid.y = grid.u = grid.v = {1.f, 2.f, 3.f};
  grid.in_image = {1, 0, 1};
  EXPECT_EQ(round_trip(grid).state, grid.state);

  introspection_labels_t labels{};
  labels.label = {introspection_labels_t::LABEL_FP, introspection_labels_t::LABEL_NONE};
  labels.stereo_state = labels.depth_state = {0, 1};
  labels.x = labels.y = labels.u = labels.v = {0.f, 1.f};
  EXPECT_EQ(round_trip(labels).label, labels.label);

  introspection_t intro{};
  intro.model_id = "m";
  intro.prob_tp = intro.prob_tn = intro.prob_fp = intro.prob_fn = {0.25f, 0.5f};
  intro.uncertainty = intro.class_variance = {0.01f, 0.02f};
  intro.query_x = intro.query_y = intro.query_u = intro.query_v = {3.f};
  intro.query_class = {3};
  intro.query_probability = intro.query_uncertainty = {0.9f};
  intro.query_announced = {1};
  intro.query_verdict = {1};
  intro.query_verdict_class = {2};
  intro.query_p_wrong = intro.query_p_wrong_variance = {0.7f};
  intro.query_verdict_announced = {0};
  const auto i = round_trip(intro);
  EXPECT_EQ(i.num_cells, 2);
  EXPECT_EQ(i.num_queries, 1);
  EXPECT_EQ(i.prob_fn, intro.prob_fn);
  EXPECT_EQ(i.query_verdict_class, intro.query_verdict_class);

  process_status_t status{};
  status.name = "p";
  status.counter_names = {"a", "b"};
  status.counter_values = {1, 2};
  EXPECT_EQ(round_trip(status).counter_values, status.counter_values);
}

TEST(Messages, SetCountsRejectsRaggedParallelArrays) {
  obstacle_grid_t grid{};
  grid.state = {0, 1};
  grid.x = {1.f};  // one short: encoding would read past the vector
  EXPECT_THROW(set_counts(grid), std::logic_error);
}

TEST(Messages, TruncatedPayloadDoesNotDecode) {
  std::mt19937 rng(2);
  stereo_image_t msg;
  msg.left = random_image(8, 8, 1, rng);
  msg.right = random_image(8, 8, 1, rng);
  set_counts(msg);
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  stereo_image_t out;
  EXPECT_LT(out.decode(buf.data(), 0, static_cast<int>(buf.size()) - 10), 0);
  depth_image_t wrong_type;
  EXPECT_LT(wrong_type.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
}

// Overwrites the big-endian int32 that ends `bytes` at `end_offset` bytes
// before its end (the array count field when the arrays are empty).
void set_count_before_end(std::vector<uint8_t>& bytes, size_t end_offset, int32_t count) {
  const auto u = static_cast<uint32_t>(count);
  const size_t at = bytes.size() - end_offset - 4;
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<size_t>(i)] = static_cast<uint8_t>(u >> (24 - 8 * i));
}

template <class Msg>
std::vector<uint8_t> encoded(Msg msg) {
  set_counts(msg);
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_GT(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  return bytes;
}

TEST(Messages, ACountTheBytesCannotHoldAllocatesNothing) {
  // lcm-gen sized arrays from the declared count before reading them: a
  // 110-byte grid declaring 2e9 cells cost every reader 2 GB.
  // GuardLcmArrays.cmake makes decode() refuse such a count first.
  auto grid_bytes = encoded(obstacle_grid_t{});  // ends: num_cells, compute_ms
  for (const int32_t count : {100000000, -1, std::numeric_limits<int32_t>::min()}) {
    set_count_before_end(grid_bytes, sizeof(double), count);
    obstacle_grid_t grid;
    EXPECT_LT(grid.decode(grid_bytes.data(), 0, static_cast<int>(grid_bytes.size())), 0) << count;
    EXPECT_EQ(grid.state.capacity(), 0u) << count;
  }
  // one cell fewer than declared is still refused, after the count check
  set_count_before_end(grid_bytes, sizeof(double), 1);
  obstacle_grid_t grid;
  EXPECT_LT(grid.decode(grid_bytes.data(), 0, static_cast<int>(grid_bytes.size()) - sizeof(double)), 0);

  auto status_bytes = encoded(process_status_t{});  // ends with num_counters
  set_count_before_end(status_bytes, 0, 1000000);
  process_status_t status;
  EXPECT_LT(status.decode(status_bytes.data(), 0, static_cast<int>(status_bytes.size())), 0);
  EXPECT_EQ(status.counter_names.capacity(), 0u);
}

}  // namespace
}  // namespace ivoa
