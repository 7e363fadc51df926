#include "server/byte_range.h"

namespace keel::server {

namespace {

// Reads a run of decimal digits at `pos` (at most 18, so it fits in int64 without overflow).
std::optional<int64_t> read_number(std::string_view text, size_t& pos) {
  size_t start = pos;
  int64_t value = 0;
  while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9') {
    if (pos - start >= 18) return std::nullopt;
    value = value * 10 + (text[pos] - '0');
    ++pos;
  }
  if (pos == start) return std::nullopt;
  return value;
}

bool consume(std::string_view text, size_t& pos, std::string_view literal) {
  if (text.substr(pos, literal.size()) != literal) return false;
  pos += literal.size();
  return true;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

}  // namespace

std::optional<ContentRange> parse_content_range(std::string_view value) {
  value = trim(value);
  size_t pos = 0;
  if (!consume(value, pos, "bytes ")) return std::nullopt;
  auto first = read_number(value, pos);
  if (!first || !consume(value, pos, "-")) return std::nullopt;
  auto last = read_number(value, pos);
  if (!last || !consume(value, pos, "/")) return std::nullopt;
  auto total = read_number(value, pos);
  if (!total || pos != value.size()) return std::nullopt;
  if (*first > *last || *last >= *total) return std::nullopt;
  return ContentRange{*first, *last, *total};
}

RangeResult parse_range(std::string_view value, uint64_t size) {
  RangeResult result;
  value = trim(value);
  size_t pos = 0;
  if (!consume(value, pos, "bytes=")) return result;
  if (value.find(',') != std::string_view::npos) return result;
  if (consume(value, pos, "-")) {  // suffix: the last n bytes
    auto suffix = read_number(value, pos);
    if (!suffix || pos != value.size()) return result;
    uint64_t n = static_cast<uint64_t>(*suffix);
    if (n == 0 || size == 0) {
      result.status = RangeStatus::kUnsatisfiable;
      return result;
    }
    if (n > size) n = size;
    result.status = RangeStatus::kSatisfiable;
    result.span = {size - n, n};
    return result;
  }
  auto first = read_number(value, pos);
  if (!first || !consume(value, pos, "-")) return result;
  uint64_t last = size == 0 ? 0 : size - 1;
  if (pos != value.size()) {
    auto explicit_last = read_number(value, pos);
    if (!explicit_last || pos != value.size() || *explicit_last < *first) return result;
    if (static_cast<uint64_t>(*explicit_last) < last) last = static_cast<uint64_t>(*explicit_last);
  }
  if (static_cast<uint64_t>(*first) >= size) {
    result.status = RangeStatus::kUnsatisfiable;
    return result;
  }
  result.status = RangeStatus::kSatisfiable;
  result.span = {static_cast<uint64_t>(*first), last - static_cast<uint64_t>(*first) + 1};
  return result;
}

std::string content_range_header(const ByteSpan& span, uint64_t size) {
  return "bytes " + std::to_string(span.offset) + "-" +
         std::to_string(span.offset + span.length - 1) + "/" + std::to_string(size);
}

std::string unsatisfied_range_header(uint64_t size) { return "bytes */" + std::to_string(size); }

}  // namespace keel::server
