// Hand-written JSON stays valid whatever a string holds.
#include <gtest/gtest.h>

#include "ivoa/core/json_text.hpp"

namespace ivoa {
namespace {

TEST(JsonQuote, PlainTextIsQuotedAsItIs) { EXPECT_EQ(json_quote("indoor_office_s3"), "\"indoor_office_s3\""); }

TEST(JsonQuote, QuotesBackslashesAndControlCharactersAreEscaped) {
  EXPECT_EQ(json_quote("say \"hi\""), "\"say \\\"hi\\\"\"");
  EXPECT_EQ(json_quote("C:\\logs"), "\"C:\\\\logs\"");
  EXPECT_EQ(json_quote("a\nb\tc"), "\"a\\nb\\tc\"");
  EXPECT_EQ(json_quote(std::string("x\x01y", 3)), "\"x\\u0001y\"");
  EXPECT_EQ(json_quote(""), "\"\"");
}

}  // namespace
}  // namespace ivoa
