#include "server/byte_range.h"

#include <gtest/gtest.h>

#include "server/url.h"

namespace keel::server {
namespace {

TEST(ContentRangeTest, ParsesTheStrictForm) {
  auto range = parse_content_range("bytes 0-4/10");
  ASSERT_TRUE(range);
  EXPECT_EQ(range->first, 0);
  EXPECT_EQ(range->last, 4);
  EXPECT_EQ(range->total, 10);
  EXPECT_EQ(range->length(), 5);
  auto big = parse_content_range("bytes 1073741824-2147483647/4294967296");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->length(), 1073741824);
  for (const char* bad :
       {"", "bytes", "bytes 0-4", "bytes 0-4/", "bytes 5-4/10", "bytes 0-10/10", "bytes -1-4/10",
        "bytes 0-4/10x", "bytes 0 -4/10", "bytes 0-4/1000000000000000000000"})
    EXPECT_FALSE(parse_content_range(bad)) << bad;
}

TEST(RangeTest, SingleRangesAgainstASize) {
  auto check = [](const char* header, uint64_t size, uint64_t offset, uint64_t length) {
    RangeResult result = parse_range(header, size);
    ASSERT_EQ(result.status, RangeStatus::kSatisfiable) << header;
    EXPECT_EQ(result.span.offset, offset) << header;
    EXPECT_EQ(result.span.length, length) << header;
  };
  check("bytes=0-9", 100, 0, 10);
  check("bytes=90-", 100, 90, 10);
  check("bytes=90-500", 100, 90, 10);
  check("bytes=-10", 100, 90, 10);
  check("bytes=-500", 100, 0, 100);
  check("bytes=99-99", 100, 99, 1);
  EXPECT_EQ(parse_range("bytes=100-", 100).status, RangeStatus::kUnsatisfiable);
  EXPECT_EQ(parse_range("bytes=-0", 100).status, RangeStatus::kUnsatisfiable);
  EXPECT_EQ(parse_range("bytes=0-", 0).status, RangeStatus::kUnsatisfiable);
  EXPECT_EQ(parse_range("bytes=5-1", 100).status, RangeStatus::kMalformed);
  EXPECT_EQ(parse_range("bytes=0-1,3-4", 100).status, RangeStatus::kMalformed);
  EXPECT_EQ(parse_range("bytes=", 100).status, RangeStatus::kMalformed);
  EXPECT_EQ(parse_range("bytes=-", 100).status, RangeStatus::kMalformed);
  EXPECT_EQ(content_range_header({90, 10}, 100), "bytes 90-99/100");
  EXPECT_EQ(unsatisfied_range_header(100), "bytes */100");
}

TEST(TargetTest, SplitsAndDecodes) {
  auto target = parse_target("/v1/missions?prefix=a%20b+c&x=1&x=2&flag");
  ASSERT_TRUE(target);
  EXPECT_EQ(target->path, "/v1/missions");
  EXPECT_EQ(target->segments, (std::vector<std::string>{"v1", "missions"}));
  EXPECT_EQ(target->query.at("prefix"), "a b c");
  EXPECT_EQ(target->query.at("x"), "2");
  EXPECT_EQ(target->query.at("flag"), "");
  auto encoded = parse_target("/v1/jobs/a%2Fb/log");
  ASSERT_TRUE(encoded);
  EXPECT_EQ(encoded->segments, (std::vector<std::string>{"v1", "jobs", "a/b", "log"}));
  EXPECT_FALSE(parse_target("http://host/v1"));
  EXPECT_FALSE(parse_target("/v1/%4"));
  EXPECT_FALSE(parse_target("/v1/%g1"));
}

}  // namespace
}  // namespace keel::server
