#include <gtest/gtest.h>

#include "core/time.h"

namespace keel {
namespace {

TEST(Time, ParsesDecimalSecondsExactly) {
  EXPECT_EQ(parse_seconds_exact("1700000000.123456789"), 1700000000123456789LL);
  EXPECT_EQ(parse_seconds_exact("12"), 12000000000LL);
  EXPECT_EQ(parse_seconds_exact("0.5"), 500000000LL);
  EXPECT_EQ(parse_seconds_exact("-0.25"), -250000000LL);
  EXPECT_EQ(parse_seconds_exact(" 3.1 "), 3100000000LL);
  EXPECT_EQ(parse_seconds_exact("1.0000000019"), 1000000001LL);  // digits past ns are cut
  for (const char* bad : {"", "abc", "1.2.3", "nan", "1e9", "."})
    EXPECT_THROW(parse_seconds_exact(bad), std::invalid_argument) << bad;
}

TEST(Time, FormatRoundTrips) {
  for (TimeNs t : {0LL, 1LL, 1700000000123456789LL, -250000000LL, -1LL})
    EXPECT_EQ(parse_seconds_exact(format_seconds(t)), t) << t;
  EXPECT_EQ(format_seconds(1500000000LL), "1.500000000");
}

}  // namespace
}  // namespace keel
