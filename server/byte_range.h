// Byte ranges of resumable uploads and ranged downloads (RFC 9110 sections 14.2-14.4),
// parsed strictly: anything else than the documented forms is rejected.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace keel::server {

// `Content-Range: bytes first-last/total` of an upload chunk (inclusive bounds).
struct ContentRange {
  int64_t first = 0;
  int64_t last = 0;
  int64_t total = 0;
  int64_t length() const { return last - first + 1; }
};

// Nullopt unless `value` is exactly "bytes a-b/N" with decimal a <= b < N.
std::optional<ContentRange> parse_content_range(std::string_view value);

// A satisfiable range of a download: bytes [offset, offset + length).
struct ByteSpan {
  uint64_t offset = 0;
  uint64_t length = 0;
};

enum class RangeStatus { kSatisfiable, kMalformed, kUnsatisfiable };

struct RangeResult {
  RangeStatus status = RangeStatus::kMalformed;
  ByteSpan span;  // set when satisfiable
};

// One range of `Range: bytes=a-b | a- | -n` against a representation of `size` bytes.
// The last position is clamped to size-1; a first position at or past the end, or a
// suffix of 0 bytes, is unsatisfiable. Several ranges ("a-b,c-d") count as malformed:
// Keel serves single ranges only.
RangeResult parse_range(std::string_view value, uint64_t size);

// "bytes a-b/size" for a 206 answer, "bytes */size" for a 416 answer.
std::string content_range_header(const ByteSpan& span, uint64_t size);
std::string unsatisfied_range_header(uint64_t size);

}  // namespace keel::server
