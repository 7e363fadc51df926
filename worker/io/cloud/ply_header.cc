#include "worker/io/cloud/ply_header.h"

#include <algorithm>

#include "worker/io/io_error.h"
#include "worker/io/mesh/mesh_parse_util.h"

namespace keel::io {
namespace {

using mesh_detail::quoted;

struct TypeName {
  const char* name;
  PlyType type;
};

// Both spellings of the PLY spec: the original (char, uchar, ...) and the sized ones.
constexpr TypeName kTypeNames[] = {
    {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
    {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
    {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
    {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
    {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
    {"float64", PlyType::kFloat64}};

// "ply \t" -> "ply": writers that pad the magic line are accepted, as they always were by the
// point-cloud reader.
std::string_view trim_trailing_blanks(std::string_view line) {
  while (!line.empty() && (line.back() == ' ' || line.back() == '\t')) line.remove_suffix(1);
  return line;
}

// Walks the header line by line; every error names the file and the current line.
class HeaderParser {
 public:
  HeaderParser(std::string_view bytes, const std::string& file)
      : lines_(bytes), bytes_size_(bytes.size()), file_(file) {}

  PlyHeader parse() {
    std::string_view line;
    if (!lines_.next(&line) || trim_trailing_blanks(line) != "ply")
      fail(1, "not a PLY file (expected the first line to be 'ply')");
    bool have_format = false;
    while (true) {
      if (!lines_.next(&line)) fail_truncated();
      const size_t n = lines_.line_number();
      mesh_detail::split_whitespace(line, &tokens_);
      if (lines_.at_end() && (tokens_.empty() || tokens_[0] != "end_header")) fail_truncated();
      if (tokens_.empty()) continue;
      const std::string_view keyword = tokens_[0];
      if (keyword == "end_header") break;
      if (keyword == "comment" || keyword == "obj_info") {
        header_.comments.emplace_back(rest_after_keyword(line));
      } else if (keyword == "format") {
        parse_format(n);
        have_format = true;
      } else if (keyword == "element") {
        parse_element(n);
      } else if (keyword == "property") {
        parse_property(n);
      } else {
        fail(n, "unknown PLY header keyword " + quoted(keyword) +
                    " (expected format, comment, obj_info, element, property or end_header)");
      }
    }
    header_.end_header_line = lines_.line_number();
    if (!have_format) fail(header_.end_header_line, "PLY header has no 'format' line");
    // An end_header without a line ending is the last byte of the file: the body is empty.
    header_.body_offset = std::min(lines_.offset(), bytes_size_);
    return std::move(header_);
  }

 private:
  [[noreturn]] void fail(size_t line, const std::string& what) const {
    throw IoError(file_ + ":" + std::to_string(line) + ": " + what);
  }

  [[noreturn]] void fail_truncated() const {
    fail(lines_.line_number(),
         "PLY header has no 'end_header' line (the file ends with no end_header: truncated?)");
  }

  static std::string_view rest_after_keyword(std::string_view line) {
    const size_t keyword = line.find_first_not_of(" \t");
    const size_t gap = line.find_first_of(" \t", keyword);
    const size_t rest = gap == std::string_view::npos ? gap : line.find_first_not_of(" \t", gap);
    return rest == std::string_view::npos ? std::string_view() : line.substr(rest);
  }

  void parse_format(size_t n) {
    const char* expected = "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'";
    if (tokens_.size() != 3) fail(n, expected);
    if (tokens_[1] == "ascii") {
      header_.format = PlyFormat::kAscii;
    } else if (tokens_[1] == "binary_little_endian") {
      header_.format = PlyFormat::kBinaryLittleEndian;
    } else if (tokens_[1] == "binary_big_endian") {
      header_.format = PlyFormat::kBinaryBigEndian;
    } else {
      fail(n, "unknown PLY format " + quoted(tokens_[1]) + ": " + expected);
    }
    double version = 0;
    if (!mesh_detail::parse_double(tokens_[2], &version) || version != 1.0)
      fail(n, "unsupported PLY version " + quoted(tokens_[2]) + " (expected 1.0)");
    header_.version = std::string(tokens_[2]);
    header_.format_line = n;
  }

  void parse_element(size_t n) {
    if (tokens_.size() != 3) fail(n, "expected 'element <name> <count>'");
    int64_t count = 0;
    if (!mesh_detail::parse_int64(tokens_[2], &count) || count < 0)
      fail(n, "bad count of element " + quoted(tokens_[1]) +
                  ": expected an integer >= 0 that fits 64 bits, got " + quoted(tokens_[2]));
    header_.elements.push_back({std::string(tokens_[1]), static_cast<uint64_t>(count), {}, n});
  }

  PlyType type_or_fail(size_t n, std::string_view name) const {
    for (const auto& [type_name, type] : kTypeNames)
      if (name == type_name) return type;
    fail(n, "unknown PLY property type " + quoted(name) +
                " (expected char, uchar, short, ushort, int, uint, float, double)");
  }

  void parse_property(size_t n) {
    if (header_.elements.empty()) fail(n, "'property' before any 'element'");
    PlyProperty property;
    property.line = n;
    if (tokens_.size() == 5 && tokens_[1] == "list") {
      property.is_list = true;
      property.count_type = type_or_fail(n, tokens_[2]);
      property.type = type_or_fail(n, tokens_[3]);
      property.name = std::string(tokens_[4]);
      if (!ply_type_is_integer(property.count_type))
        fail(n, "list count type must be an integer type, got " + quoted(tokens_[2]));
    } else if (tokens_.size() == 3 && tokens_[1] != "list") {
      property.type = type_or_fail(n, tokens_[1]);
      property.name = std::string(tokens_[2]);
    } else {
      fail(n, "expected 'property <type> <name>' or 'property list <type> <type> <name>'");
    }
    PlyElement& element = header_.elements.back();
    for (const auto& other : element.properties)
      if (other.name == property.name)
        fail(n, "element '" + element.name + "' declares property '" + property.name +
                    "' twice (first on line " + std::to_string(other.line) + ")");
    element.properties.push_back(std::move(property));
  }

  mesh_detail::LineCursor lines_;
  size_t bytes_size_;
  const std::string& file_;
  std::vector<std::string_view> tokens_;
  PlyHeader header_;
};

}  // namespace

size_t ply_type_size(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool ply_type_is_integer(PlyType type) {
  return type != PlyType::kFloat32 && type != PlyType::kFloat64;
}

const char* to_string(PlyFormat format) {
  switch (format) {
    case PlyFormat::kAscii:
      return "ascii";
    case PlyFormat::kBinaryLittleEndian:
      return "binary_little_endian";
    case PlyFormat::kBinaryBigEndian:
      return "binary_big_endian";
  }
  return "";
}

PlyHeader parse_ply_header(std::string_view bytes, const std::string& file) {
  return HeaderParser(bytes, file).parse();
}

}  // namespace keel::io
