// Range headers and base URLs against hand-written values.
#include "client/http_ranges.h"

#include <gtest/gtest.h>

#include "client/http_url.h"

namespace keel::client {
namespace {

TEST(HttpRanges, ContentRangeOfChunks) {
  // A 40 MiB file in 16 MiB chunks: [0, 16777215], [16777216, 33554431], [33554432, 41943039].
  const int64_t total = 40ll << 20;
  EXPECT_EQ(content_range_header(0, (16ll << 20) - 1, total), "bytes 0-16777215/41943040");
  EXPECT_EQ(content_range_header(16ll << 20, (32ll << 20) - 1, total),
            "bytes 16777216-33554431/41943040");
  EXPECT_EQ(content_range_header(32ll << 20, total - 1, total), "bytes 33554432-41943039/41943040");
  EXPECT_EQ(content_range_header(0, 0, 1), "bytes 0-0/1");
  // Sizes past 4 GiB must not wrap.
  EXPECT_EQ(content_range_header(5000000000ll, 5000000099ll, 6000000000ll),
            "bytes 5000000000-5000000099/6000000000");
}

TEST(HttpRanges, RangeFromOffset) {
  EXPECT_EQ(range_from_header(0), "bytes=0-");
  EXPECT_EQ(range_from_header(150000), "bytes=150000-");
  EXPECT_EQ(range_from_header(8589934592ll), "bytes=8589934592-");
}

TEST(HttpRanges, ParsesContentRange) {
  const auto full = parse_content_range("bytes 100-199/1000");
  ASSERT_TRUE(full);
  EXPECT_EQ(full->first, 100);
  EXPECT_EQ(full->last, 199);
  EXPECT_EQ(full->total, 1000);
  const auto unsatisfied = parse_content_range("bytes */1000");
  ASSERT_TRUE(unsatisfied);
  EXPECT_EQ(unsatisfied->first, -1);
  EXPECT_EQ(unsatisfied->total, 1000);
  const auto unknown_total = parse_content_range("bytes 0-9/*");
  ASSERT_TRUE(unknown_total);
  EXPECT_EQ(unknown_total->total, -1);
  for (const char* bad : {"", "bytes", "bytes 5-4/10", "bytes 0-10/10", "bits 0-1/2",
                          "bytes -1-2/3", "bytes 0-1", "bytes */*", "bytes 1-2/3x", "bytes 0-/10"})
    EXPECT_FALSE(parse_content_range(bad)) << bad;
}

TEST(HttpUrl, ParsesBaseUrls) {
  const BaseUrl a = parse_base_url("http://127.0.0.1:8080");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, "8080");
  EXPECT_EQ(a.path_prefix, "");
  const BaseUrl b = parse_base_url("http://keel.example/api/");
  EXPECT_EQ(b.host, "keel.example");
  EXPECT_EQ(b.port, "80");
  EXPECT_EQ(b.path_prefix, "/api");
  const BaseUrl c = parse_base_url("http://[::1]:9000");
  EXPECT_EQ(c.host, "::1");
  EXPECT_EQ(c.port, "9000");
  const BaseUrl d = parse_base_url("https://keel.example.org");
  EXPECT_TRUE(d.tls);
  EXPECT_EQ(d.port, "443");
  EXPECT_EQ(d.origin(), "https://keel.example.org:443");
  EXPECT_FALSE(c.tls);
  for (const char* bad : {"ftp://h:1", "h:1", "http://", "http://h:", "http://h:99999",
                          "http://h:x1", "http://u:p@h:1", "https://", "httpss://h:1"})
    EXPECT_THROW(parse_base_url(bad), std::invalid_argument) << bad;
}

TEST(HttpUrl, EncodesQueryValues) {
  EXPECT_EQ(url_encode("usv-bridge_1.a~"), "usv-bridge_1.a~");
  EXPECT_EQ(url_encode("a b&c=d/é"), "a%20b%26c%3Dd%2F%C3%A9");
}

}  // namespace
}  // namespace keel::client
