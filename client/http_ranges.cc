#include "client/http_ranges.h"

#include <charconv>

namespace keel::client {

std::string content_range_header(int64_t first, int64_t last, int64_t total) {
  return "bytes " + std::to_string(first) + "-" + std::to_string(last) + "/" +
         std::to_string(total);
}

std::string range_from_header(int64_t offset) { return "bytes=" + std::to_string(offset) + "-"; }

namespace {
// Parses a whole non-negative decimal; false on anything else.
bool parse_count(std::string_view text, int64_t& out) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size() && out >= 0;
}
}  // namespace

std::optional<ContentRange> parse_content_range(std::string_view header) {
  constexpr std::string_view kUnit = "bytes ";
  if (header.substr(0, kUnit.size()) != kUnit) return std::nullopt;
  header.remove_prefix(kUnit.size());
  const size_t slash = header.find('/');
  if (slash == std::string_view::npos) return std::nullopt;
  const std::string_view range = header.substr(0, slash);
  const std::string_view total = header.substr(slash + 1);
  ContentRange out;
  if (total != "*" && !parse_count(total, out.total)) return std::nullopt;
  if (range == "*") {
    if (out.total < 0) return std::nullopt;
    return out;
  }
  const size_t dash = range.find('-');
  if (dash == std::string_view::npos) return std::nullopt;
  if (!parse_count(range.substr(0, dash), out.first) ||
      !parse_count(range.substr(dash + 1), out.last))
    return std::nullopt;
  if (out.last < out.first || (out.total >= 0 && out.last >= out.total)) return std::nullopt;
  return out;
}

}  // namespace keel::client
