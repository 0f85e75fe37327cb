// --expect CHANNEL=N arguments: what is accepted, and that anything else is
// refused with the argument named instead of aborting the tool.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "ivoa/core/channel_counts.hpp"

namespace ivoa {
namespace {

TEST(ChannelCounts, PairsBecomeCountsPerChannel) {
  const auto counts = parse_channel_counts({"STEREO_IMAGES=60", "DEPTH_IMAGE=0"}, "--expect");
  ASSERT_EQ(counts.size(), 2u);
  EXPECT_EQ(counts.at("STEREO_IMAGES"), 60);
  EXPECT_EQ(counts.at("DEPTH_IMAGE"), 0);
}

TEST(ChannelCounts, AnythingElseIsRefusedByName) {
  for (const std::string bad : {"STEREO_IMAGES", "STEREO_IMAGES=", "STEREO_IMAGES=sixty", "STEREO_IMAGES=6x", "=3",
                                "A=B=3", "STEREO_IMAGES=-1", "STEREO_IMAGES=99999999999999999999"}) {
    try {
      parse_channel_counts({"OK=1", bad}, "--expect");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--expect " + bad + ": use CHANNEL=N", 0), 0u) << e.what();
    }
  }
}

// The last of two counts for one channel silently won (ivoa-log-check
// --expect A=4 A=3 passed a log of 3).
TEST(ChannelCounts, AChannelGivenTwiceIsRefused) {
  try {
    parse_channel_counts({"STEREO_IMAGES=4", "DEPTH_IMAGE=4", "STEREO_IMAGES=3"}, "--expect");
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "--expect STEREO_IMAGES is given twice (=4 and =3)");
  }
}

}  // namespace
}  // namespace ivoa
