// HTTP Range and Content-Range parsing (server/byte_range.h): any header text either parses
// into a span inside the resource or is refused; never out of bounds.
#include <cstdlib>
#include <string_view>

#include "server/byte_range.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const std::string_view text(reinterpret_cast<const char*>(input.data), input.size);
  if (const auto range = keel::server::parse_content_range(text)) {
    // A parsed chunk range is ordered and inside its total (docs/api.md).
    if (range->first < 0 || range->first > range->last || range->last >= range->total) std::abort();
  }
  const uint64_t resource_size = input.selector * 977u;
  const auto result = keel::server::parse_range(text, resource_size);
  if (result.status == keel::server::RangeStatus::kSatisfiable &&
      (result.span.length == 0 || result.span.offset >= resource_size ||
       result.span.length > resource_size - result.span.offset))
    std::abort();
  return 0;
}
