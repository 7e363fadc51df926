#include "worker/io/cloud/pcd_header_check.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <optional>
#include <vector>

#include "worker/io/io_error.h"

namespace keel::io {

namespace {

// LZF copies at most 264 bytes for a 3-byte back reference.
constexpr uint64_t kMaxLzfExpansion = 88;

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

std::optional<uint64_t> parse_unsigned(std::string_view token) {
  uint64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

struct Declared {
  std::vector<std::string_view> fields, sizes, types, counts;
  std::optional<uint64_t> width, height, points;
  std::string_view encoding;
  size_t data_offset = 0;  // the byte after the DATA line
};

[[noreturn]] void malformed(const std::string& name, const std::string& what) {
  throw IoError(name + ": malformed PCD header: " + what);
}

// The values of a per-field line, once, one per field (checked when FIELDS is known).
void keep_values(const std::vector<std::string_view>& tokens, const char* keyword,
                 std::vector<std::string_view>* out, const std::string& name) {
  if (!out->empty()) malformed(name, std::string(keyword) + " is given twice");
  out->assign(tokens.begin() + 1, tokens.end());
  if (out->empty()) malformed(name, std::string(keyword) + " has no values");
}

void keep_integer(const std::vector<std::string_view>& tokens, const char* keyword,
                  std::optional<uint64_t>* out, const std::string& name) {
  if (out->has_value()) malformed(name, std::string(keyword) + " is given twice");
  const std::optional<uint64_t> value =
      tokens.size() == 2 ? parse_unsigned(tokens[1]) : std::nullopt;
  if (!value || *value > UINT32_MAX)
    malformed(name, std::string(keyword) + " is '" +
                        std::string(tokens.size() > 1 ? tokens[1] : "") +
                        "' (expected one integer in 0..4294967295)");
  *out = value;
}

constexpr std::string_view kKeywords[] = {"VERSION",   "FIELDS", "COLUMNS", "SIZE",
                                          "TYPE",      "COUNT",  "WIDTH",   "HEIGHT",
                                          "VIEWPOINT", "POINTS", "DATA"};

// A header line's words. PCL trims and splits its lines at spaces, tabs and carriage returns
// (files written on Windows end their lines in "\r\n"), and reads numbers as streams do,
// past any whitespace.
void split_words(std::string_view line, std::vector<std::string_view>* words) {
  constexpr std::string_view kSpace = " \t\r\v\f";
  words->clear();
  size_t i = line.find_first_not_of(kSpace);
  while (i != std::string_view::npos) {
    const size_t end = line.find_first_of(kSpace, i);
    words->push_back(line.substr(i, end == std::string_view::npos ? end : end - i));
    i = end == std::string_view::npos ? end : line.find_first_not_of(kSpace, end);
  }
}

// Whether a line whose first token is `token`, cut at its end, could be a header line.
bool may_be_header(std::string_view token) {
  if (token.empty() || starts_with(token, "#")) return true;
  for (const std::string_view keyword : kKeywords)
    if (starts_with(token, keyword) || starts_with(keyword, token)) return true;
  return false;
}

// The header as PCL's readHeader reads it: line by line, skipping empty lines and comments,
// until the first line that is not a header keyword. DATA does not end it: PCL goes on reading
// keywords after DATA (a POINTS line there resized its cloud), so neither does this.
Declared read_declared(std::string_view head, bool whole_file, const std::string& name) {
  Declared d;
  bool data_seen = false;
  std::vector<std::string_view> tokens;
  const size_t head_size = head.size();
  while (!head.empty()) {
    const size_t end = head.find('\n');
    const std::string_view line = head.substr(0, end);
    head = end == std::string_view::npos ? std::string_view() : head.substr(end + 1);
    split_words(line, &tokens);
    if (end == std::string_view::npos && !whole_file) {  // cut by the end of what was read
      if (tokens.empty() || may_be_header(tokens[0]))
        malformed(name, "the header runs past its first " + std::to_string(kPcdHeaderBytes / 1024) +
                            " KiB");
      break;
    }
    if (tokens.empty() || starts_with(tokens[0], "#")) continue;
    const std::string_view key = tokens[0];
    if (starts_with(key, "VERSION") || starts_with(key, "VIEWPOINT")) continue;
    if (starts_with(key, "DATA")) {
      if (data_seen) malformed(name, "DATA is given twice");
      data_seen = true;
      d.encoding = tokens.size() > 1 ? tokens[1] : std::string_view();
      d.data_offset = head_size - head.size();
    } else if (starts_with(key, "FIELDS") || starts_with(key, "COLUMNS")) {
      keep_values(tokens, "FIELDS", &d.fields, name);
    } else if (starts_with(key, "SIZE")) {
      keep_values(tokens, "SIZE", &d.sizes, name);
    } else if (starts_with(key, "TYPE")) {
      keep_values(tokens, "TYPE", &d.types, name);
    } else if (starts_with(key, "COUNT")) {
      keep_values(tokens, "COUNT", &d.counts, name);
    } else if (starts_with(key, "WIDTH")) {
      keep_integer(tokens, "WIDTH", &d.width, name);
    } else if (starts_with(key, "HEIGHT")) {
      keep_integer(tokens, "HEIGHT", &d.height, name);
    } else if (starts_with(key, "POINTS")) {
      keep_integer(tokens, "POINTS", &d.points, name);
    } else {
      break;  // the header ends (the body, or a line PCL stops at)
    }
  }
  if (!data_seen) malformed(name, "no DATA line (truncated header?)");
  return d;
}

// Bytes of one point: the sum of SIZE x COUNT (a field without SIZE is a 4-byte float, as in
// PCD v0.5 and PCL; without COUNT it holds one value).
uint64_t point_bytes(const Declared& d, const std::string& name,
                     std::vector<PackedField>* fields = nullptr) {
  if (d.fields.empty()) malformed(name, "no FIELDS");
  const size_t n = d.fields.size();
  for (const auto& [values, keyword] :
       {std::pair{&d.sizes, "SIZE"}, std::pair{&d.types, "TYPE"}, std::pair{&d.counts, "COUNT"}})
    if (!values->empty() && values->size() != n)
      malformed(name, std::string(keyword) + " has " + std::to_string(values->size()) +
                          " values for " + std::to_string(n) + " FIELDS");
  uint64_t bytes = 0;
  for (size_t k = 0; k < n; ++k) {
    uint64_t size = 4, count = 1;
    if (!d.sizes.empty()) {
      const std::optional<uint64_t> s = parse_unsigned(d.sizes[k]);
      if (!s || (*s != 1 && *s != 2 && *s != 4 && *s != 8))
        malformed(name, "SIZE of field '" + std::string(d.fields[k]) + "' is '" +
                            std::string(d.sizes[k]) + "' (expected 1, 2, 4 or 8 bytes)");
      size = *s;
    }
    if (!d.types.empty() && d.types[k] != "I" && d.types[k] != "U" && d.types[k] != "F")
      malformed(name, "TYPE of field '" + std::string(d.fields[k]) + "' is '" +
                          std::string(d.types[k]) + "' (expected I, U or F)");
    if (!d.counts.empty()) {
      const std::optional<uint64_t> c = parse_unsigned(d.counts[k]);
      if (!c || *c == 0 || *c > kMaxPcdFieldCount)
        malformed(name, "COUNT value " + std::to_string(k + 1) + " is '" +
                            std::string(d.counts[k]) + "' (expected 1.." +
                            std::to_string(kMaxPcdFieldCount) + " values per field)");
      count = *c;
    }
    if (fields) {
      const char type = d.types.empty() ? 'F' : d.types[k][0];
      const std::optional<FieldType> field_type = pcd_field_type(type, size);
      if (!field_type)
        malformed(name, "field '" + std::string(d.fields[k]) + "' is TYPE F of SIZE " +
                            std::to_string(size) + " (floats are 4 or 8 bytes)");
      fields->push_back({std::string(d.fields[k]), *field_type, static_cast<size_t>(bytes),
                         static_cast<size_t>(count)});
    }
    bytes += size * count;
  }
  return bytes;
}

}  // namespace

std::optional<FieldType> pcd_field_type(char type, uint64_t size) {
  switch (type) {
    case 'I':
      return size == 1   ? FieldType::kInt8
             : size == 2 ? FieldType::kInt16
             : size == 4 ? FieldType::kInt32
                         : FieldType::kInt64;
    case 'U':
      return size == 1   ? FieldType::kUint8
             : size == 2 ? FieldType::kUint16
             : size == 4 ? FieldType::kUint32
                         : FieldType::kUint64;
    case 'F':
      if (size == 4) return FieldType::kFloat32;
      if (size == 8) return FieldType::kFloat64;
      return std::nullopt;
    default:
      return std::nullopt;
  }
}

void check_pcd_header(std::string_view head, uint64_t file_size, const std::string& name) {
  (void)parse_pcd_header(head, file_size, name);
}

PcdLayout parse_pcd_header(std::string_view head, uint64_t file_size, const std::string& name) {
  const Declared d = read_declared(head, head.size() >= file_size, name);
  PcdLayout layout;
  const uint64_t step = point_bytes(d, name, &layout.fields);
  uint64_t values = 0;  // per point
  for (size_t k = 0; k < d.fields.size(); ++k)
    values += d.counts.empty() ? 1 : *parse_unsigned(d.counts[k]);
  // WIDTH x HEIGHT and POINTS are below 2^32 each, the point size below 2^36: the products
  // below are exact in 128 bits.
  using Wide = unsigned __int128;
  const Wide points =
      std::max<Wide>(d.points.value_or(0), Wide(d.width.value_or(0)) * d.height.value_or(1));
  const std::string declared =
      std::to_string(static_cast<uint64_t>(std::min<Wide>(points, UINT64_MAX)));
  if (starts_with(d.encoding, "binary_compressed")) {
    if (points * step > Wide(file_size) * kMaxLzfExpansion)
      malformed(name, declared + " points of " + std::to_string(step) + " bytes cannot be in " +
                          std::to_string(file_size) + " bytes of LZF (it expands at most " +
                          std::to_string(kMaxLzfExpansion) + " times)");
  } else if (starts_with(d.encoding, "binary")) {
    if (points * step > file_size)
      throw IoError(name + ": truncated PCD: " + declared + " points of " + std::to_string(step) +
                    " bytes do not fit in the whole file's " + std::to_string(file_size) +
                    " bytes");
  } else if (points * values > file_size) {  // ascii: a value takes a byte at the least
    throw IoError(name + ": truncated PCD: " + declared + " points of " + std::to_string(values) +
                  " values do not fit in the whole file's " + std::to_string(file_size) + " bytes");
  }
  if (d.encoding == "ascii")
    layout.encoding = PcdEncoding::kAscii;
  else if (d.encoding == "binary")
    layout.encoding = PcdEncoding::kBinary;
  else if (d.encoding == "binary_compressed")
    layout.encoding = PcdEncoding::kBinaryCompressed;
  else
    malformed(name, "DATA is '" + std::string(d.encoding) +
                        "' (expected ascii, binary or binary_compressed)");
  // PCD v0.5 had neither WIDTH nor HEIGHT: an unorganised cloud of POINTS points.
  layout.width = d.width.value_or(d.points.value_or(0));
  layout.height = d.height.value_or(1);
  layout.points = uint64_t{layout.width} * layout.height;
  if (d.points && *d.points != layout.points)
    malformed(name, "WIDTH x HEIGHT is " + std::to_string(layout.points) + ", POINTS " +
                        std::to_string(*d.points));
  layout.point_step = static_cast<size_t>(step);
  layout.data_offset = d.data_offset;
  layout.values_per_point = static_cast<size_t>(values);
  return layout;
}

}  // namespace keel::io
