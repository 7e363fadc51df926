// Byte-range headers of resumable transfers (RFC 9110 section 14).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace keel::client {

// "bytes first-last/total" for a PUT chunk holding bytes [first, last].
std::string content_range_header(int64_t first, int64_t last, int64_t total);
// "bytes=offset-": the rest of a resource from `offset`.
std::string range_from_header(int64_t offset);

struct ContentRange {
  int64_t first = -1;  // -1 for the unsatisfied form "bytes */total"
  int64_t last = -1;
  int64_t total = -1;  // -1 when the server wrote '*'
};
// Parses "bytes a-b/N", "bytes a-b/*" and "bytes */N"; nullopt when malformed.
std::optional<ContentRange> parse_content_range(std::string_view header);

}  // namespace keel::client
