// Channel selection: whole-name regexes, exclude over include, and the
// always-recorded calibration channel.
#include <gtest/gtest.h>

#include "ivoa/logio/channel_filter.hpp"

namespace ivoa::logio {
namespace {

TEST(ChannelFilter, IncludeRegexMustMatchTheWholeName) {
  ChannelFilter filter("STEREO_.*|DEPTH_IMAGE", "");
  EXPECT_TRUE(filter.accepts("STEREO_IMAGES"));
  EXPECT_TRUE(filter.accepts("DEPTH_IMAGE"));
  EXPECT_FALSE(filter.accepts("DEPTH_IMAGE_PREVIEW"));
  EXPECT_FALSE(filter.accepts("MY_STEREO_IMAGES"));
  EXPECT_FALSE(filter.accepts("PROCESS_STATUS"));
}

TEST(ChannelFilter, ExcludeWinsOverInclude) {
  ChannelFilter filter(".*", "PROCESS_STATUS|.*_PREVIEW");
  EXPECT_TRUE(filter.accepts("STEREO_IMAGES"));
  EXPECT_FALSE(filter.accepts("PROCESS_STATUS"));
  EXPECT_FALSE(filter.accepts("STEREO_PREVIEW"));
  EXPECT_FALSE(filter.accepts("STEREO_PREVIEW"));  // cached decision, same answer
}

TEST(ChannelFilter, AlwaysRecordedChannelsIgnoreBothRegexes) {
  ChannelFilter filter("STEREO_IMAGES", "RIG_.*", {"RIG_CALIBRATION"});
  EXPECT_TRUE(filter.accepts("RIG_CALIBRATION"));
  EXPECT_FALSE(filter.accepts("RIG_OTHER"));
}

TEST(ChannelFilter, ABadRegexIsAnInvalidArgumentNamingIt) {
  try {
    ChannelFilter filter("STEREO_(", "");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("STEREO_("), std::string::npos) << e.what();
  }
  EXPECT_THROW(ChannelFilter(".*", "[z-a]"), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa::logio
