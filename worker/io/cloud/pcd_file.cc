// PCD (PCL's point cloud format, v0.7: https://pointclouds.org/documentation/tutorials/
// pcd_file_format.html) read and written by Keel itself: the header checked (pcd_header_check.h),
// binary bodies used in place, binary_compressed bodies LZF-decoded (lzf.h) and turned from
// field-major back into point records, ascii rows parsed into records. PCL's own reader pulled
// VTK and ~70 shared libraries into every program that reads a scan.
#include <algorithm>
#include <charconv>
#include <cstring>
#include <fstream>
#include <optional>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/replaced_file.h"
#include "worker/io/cloud/lzf.h"
#include "worker/io/cloud/pcd_header_check.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/mapped_file.h"
#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

const char* kEncodings[] = {"ascii", "binary", "binary_compressed"};

std::string encoding_name(PcdEncoding e) { return kEncodings[static_cast<int>(e)]; }

// The fields a reader sees: PCL's padding fields ("_") hold no values.
std::vector<PackedField> visible_fields(const PcdLayout& layout) {
  std::vector<PackedField> fields;
  for (const auto& f : layout.fields)
    if (f.name != "_") fields.push_back(f);
  return fields;
}

PcdLayout read_layout(std::string_view bytes, const std::string& name) {
  const std::string_view head(bytes.data(), std::min(bytes.size(), kPcdHeaderBytes));
  PcdLayout layout = parse_pcd_header(head, bytes.size(), name);
  if (layout.fields.empty() || layout.point_step == 0)
    throw IoError(name + ": malformed PCD header: no FIELDS (or fields of no size)");
  return layout;
}

// binary_compressed: uint32 compressed size, uint32 uncompressed size, then LZF of the body
// stored field by field (every point's first field, then every point's second...). The
// columns are read where they are (PackedField::stride), not turned back into records: a
// second body-sized buffer costs more than its copy on a machine where fresh pages are dear.
std::vector<uint8_t> decompressed_columns(std::string_view bytes, const PcdLayout& h,
                                          const std::string& name) {
  const uint64_t body = h.points * h.point_step;
  if (bytes.size() < h.data_offset + 8)
    throw IoError(name + ": truncated PCD: missing the binary_compressed size header");
  uint32_t sizes[2];  // compressed, uncompressed
  std::memcpy(sizes, bytes.data() + h.data_offset, 8);
  const uint64_t available = bytes.size() - h.data_offset - 8;
  if (sizes[0] > available)
    throw IoError(name + ": truncated PCD: compressed body of " + std::to_string(sizes[0]) +
                  " bytes, the file has " + std::to_string(available));
  if (sizes[1] != body)
    throw IoError(name + ": malformed PCD: compressed body unpacks to " + std::to_string(sizes[1]) +
                  " bytes, the header needs " + std::to_string(body));
  // LZF copies at most 264 bytes for a 3-byte back reference: a body claiming more than 88
  // times its compressed size is not LZF (and would be allocated before reading it).
  if (sizes[1] > 88ull * sizes[0] + 8)
    throw IoError(name + ": malformed PCD: a compressed body of " + std::to_string(sizes[0]) +
                  " bytes cannot unpack to " + std::to_string(sizes[1]) +
                  " (LZF expands at most 88 times)");
  const auto* in = reinterpret_cast<const uint8_t*>(bytes.data() + h.data_offset + 8);
  std::optional<std::vector<uint8_t>> columns = lzf_decompress(in, sizes[0], sizes[1]);
  if (!columns)
    throw IoError(name + ": malformed PCD: the binary_compressed body is not valid LZF (" +
                  std::to_string(sizes[0]) + " bytes to unpack to " + std::to_string(sizes[1]) +
                  ")");
  return std::move(*columns);
}

// The fields of decompressed_columns(): each its own column, one value every field width.
std::vector<PackedField> column_fields(const PcdLayout& h) {
  std::vector<PackedField> fields;
  size_t column_start = 0;
  for (const auto& f : h.fields) {
    const size_t width = field_size(f.type) * f.count;
    if (f.name != "_") fields.push_back({f.name, f.type, column_start, f.count, width});
    column_start += width * static_cast<size_t>(h.points);
  }
  return fields;
}

template <typename T>
bool parse_as(std::string_view token, uint8_t* out) {
  T value{};
  if constexpr (std::is_floating_point_v<T>) {
    double d = 0;
    if (!mesh_detail::parse_double(token, &d)) return false;
    value = static_cast<T>(d);
  } else {
    const char* first = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
    const auto [end, ec] = std::from_chars(first, token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size()) {
      double d = 0;  // "3.0" or "1e3" written for an integer field: taken when it is whole
      if (!mesh_detail::parse_double(token, &d) || d != static_cast<double>(static_cast<T>(d)))
        return false;
      value = static_cast<T>(d);
    }
  }
  std::memcpy(out, &value, sizeof value);
  return true;
}

bool parse_value(FieldType type, std::string_view token, uint8_t* out) {
  switch (type) {
    case FieldType::kInt8:
      return parse_as<int8_t>(token, out);
    case FieldType::kUint8:
      return parse_as<uint8_t>(token, out);
    case FieldType::kInt16:
      return parse_as<int16_t>(token, out);
    case FieldType::kUint16:
      return parse_as<uint16_t>(token, out);
    case FieldType::kInt32:
      return parse_as<int32_t>(token, out);
    case FieldType::kUint32:
      return parse_as<uint32_t>(token, out);
    case FieldType::kInt64:
      return parse_as<int64_t>(token, out);
    case FieldType::kUint64:
      return parse_as<uint64_t>(token, out);
    case FieldType::kFloat32:
      return parse_as<float>(token, out);
    case FieldType::kFloat64:
      return parse_as<double>(token, out);
  }
  return false;
}

// ascii: one row per point of values_per_point numbers (every COUNT element of every field,
// padding included), blank lines skipped; rows short, long, missing or beyond POINTS refused
// naming the line.
std::vector<uint8_t> ascii_records(std::string_view bytes, const PcdLayout& h,
                                   const std::string& name) {
  std::vector<uint8_t> records(h.points * h.point_step);
  std::string_view rest(bytes);
  rest.remove_prefix(std::min(rest.size(), h.data_offset));
  size_t line_number = static_cast<size_t>(
      std::count(bytes.begin(), bytes.begin() + std::min(bytes.size(), h.data_offset), '\n'));
  uint64_t rows = 0;
  std::vector<std::string_view> tokens;
  while (!rest.empty()) {
    const size_t end = rest.find('\n');
    const std::string_view line = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
    ++line_number;
    mesh_detail::split_whitespace(line, &tokens);
    if (tokens.empty()) continue;
    if (rows == h.points) {
      uint64_t extra = 1;
      for (std::string_view more = rest; !more.empty();) {
        const size_t e = more.find('\n');
        mesh_detail::split_whitespace(more.substr(0, e), &tokens);
        extra += tokens.empty() ? 0 : 1;
        more = e == std::string_view::npos ? std::string_view() : more.substr(e + 1);
      }
      throw IoError(name + ":" + std::to_string(line_number) + ": " + std::to_string(extra) +
                    " data rows beyond the " + std::to_string(h.points) +
                    " points the header declares (POINTS " + std::to_string(h.points) + ")");
    }
    const std::string where =
        name + ":" + std::to_string(line_number) + ": data row " + std::to_string(rows + 1) + ": ";
    if (tokens.size() != h.values_per_point)
      throw IoError(where + "expected " + std::to_string(h.values_per_point) +
                    " values (the sum of COUNT over FIELDS), found " +
                    std::to_string(tokens.size()));
    uint8_t* record = records.data() + rows * h.point_step;
    size_t t = 0;
    for (const auto& f : h.fields) {
      const size_t size = field_size(f.type);
      for (size_t k = 0; k < f.count; ++k, ++t)
        if (!parse_value(f.type, tokens[t], record + f.offset + k * size))
          throw IoError(where + "expected a number, got '" + std::string(tokens[t]) + "'" +
                        " (field '" + f.name + "', " + to_string(f.type) + ")");
    }
    ++rows;
  }
  if (rows < h.points)
    throw IoError(name + ": truncated PCD: POINTS declares " + std::to_string(h.points) +
                  " points, the ascii body has " + std::to_string(rows) + " rows");
  return records;
}

char type_letter(FieldType type) {
  if (type == FieldType::kFloat32 || type == FieldType::kFloat64) return 'F';
  switch (type) {
    case FieldType::kInt8:
    case FieldType::kInt16:
    case FieldType::kInt32:
    case FieldType::kInt64:
      return 'I';
    default:
      return 'U';
  }
}

template <typename T>
void append_value(std::string& out, const uint8_t* at) {
  T value;
  std::memcpy(&value, at, sizeof value);
  char text[64];
  // Shortest text that reads back to the same value (floats and integers alike).
  const auto result = std::to_chars(text, text + sizeof text, value);
  out.append(text, result.ptr);
}

void append_ascii_value(std::string& out, FieldType type, const uint8_t* at) {
  switch (type) {
    case FieldType::kInt8:
      return append_value<int8_t>(out, at);
    case FieldType::kUint8:
      return append_value<uint8_t>(out, at);
    case FieldType::kInt16:
      return append_value<int16_t>(out, at);
    case FieldType::kUint16:
      return append_value<uint16_t>(out, at);
    case FieldType::kInt32:
      return append_value<int32_t>(out, at);
    case FieldType::kUint32:
      return append_value<uint32_t>(out, at);
    case FieldType::kInt64:
      return append_value<int64_t>(out, at);
    case FieldType::kUint64:
      return append_value<uint64_t>(out, at);
    case FieldType::kFloat32:
      return append_value<float>(out, at);
    case FieldType::kFloat64:
      return append_value<double>(out, at);
  }
}

}  // namespace

ScanFileInfo read_pcd_info(const fs::path& path) {
  const std::string name = display_path(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(name + ": not found");
  std::ifstream in(path, std::ios::binary);
  std::string head(kPcdHeaderBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  const PcdLayout h = parse_pcd_header(head, fs::file_size(path), name);
  if (h.fields.empty() || h.point_step == 0)
    throw IoError(name + ": malformed PCD header: no FIELDS (or fields of no size)");
  ScanFileInfo info;
  info.num_points = static_cast<size_t>(h.points);
  info.fields = visible_fields(h);
  info.format = "pcd " + encoding_name(h.encoding);
  return info;
}

PointCloud read_pcd(const fs::path& path, TimeNs t_ns, const ScanReadOptions& options) {
  const std::string name = display_path(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(name + ": not found");
  const MappedFile mapped(path);
  const std::string_view bytes = mapped.bytes();
  const PcdLayout h = read_layout(bytes, name);
  const size_t points = static_cast<size_t>(h.points);
  if (h.encoding == PcdEncoding::kBinary) {
    const uint64_t body = h.points * h.point_step;
    if (h.data_offset + body > bytes.size())
      throw IoError(name + ": truncated PCD: " + std::to_string(points) + " points of " +
                    std::to_string(h.point_step) + " bytes need " + std::to_string(body) +
                    " bytes of data, the file has " +
                    std::to_string(bytes.size() - std::min(bytes.size(), h.data_offset)));
    const PackedCloudView view{reinterpret_cast<const uint8_t*>(bytes.data() + h.data_offset),
                               points, h.point_step, visible_fields(h)};
    return unpack_cloud(view, t_ns, options, name);
  }
  if (h.encoding == PcdEncoding::kBinaryCompressed) {
    const std::vector<uint8_t> columns = decompressed_columns(bytes, h, name);
    return unpack_cloud({columns.data(), points, h.point_step, column_fields(h)}, t_ns, options,
                        name);
  }
  const std::vector<uint8_t> records = ascii_records(bytes, h, name);
  return unpack_cloud({records.data(), points, h.point_step, visible_fields(h)}, t_ns, options,
                      name);
}

void write_pcd(const fs::path& path, const PointCloud& cloud, const ScanWriteOptions& options) {
  const PackedCloud packed = pack_cloud(cloud, options.time);
  const PcdEncoding encoding = options.encoding == ScanEncoding::kAscii ? PcdEncoding::kAscii
                               : options.encoding == ScanEncoding::kBinary
                                   ? PcdEncoding::kBinary
                                   : PcdEncoding::kBinaryCompressed;
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS";
  for (const auto& f : packed.fields) header += " " + f.name;
  header += "\nSIZE";
  for (const auto& f : packed.fields) header += " " + std::to_string(field_size(f.type));
  header += "\nTYPE";
  for (const auto& f : packed.fields) header += std::string(" ") + type_letter(f.type);
  header += "\nCOUNT";
  for (size_t k = 0; k < packed.fields.size(); ++k) header += " 1";
  const std::string n = std::to_string(packed.num_points);
  header += "\nWIDTH " + n + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + n + "\nDATA " +
            encoding_name(encoding) + "\n";

  ReplacedFile file(path);
  file.append(header.data(), header.size());
  if (encoding == PcdEncoding::kBinary) {
    file.append(reinterpret_cast<const char*>(packed.data.data()), packed.data.size());
  } else if (encoding == PcdEncoding::kBinaryCompressed) {
    std::vector<uint8_t> columns(packed.data.size());
    size_t column_start = 0;
    for (const auto& f : packed.fields) {
      const size_t width = field_size(f.type);
      for (size_t p = 0; p < packed.num_points; ++p)
        std::memcpy(columns.data() + column_start + p * width,
                    packed.data.data() + p * packed.point_step + f.offset, width);
      column_start += width * packed.num_points;
    }
    const std::vector<uint8_t> compressed = lzf_compress(columns.data(), columns.size());
    if (compressed.size() > UINT32_MAX || columns.size() > UINT32_MAX)
      throw IoError(path.string() + ": a binary_compressed PCD body is limited to 4 GiB");
    const uint32_t sizes[2] = {static_cast<uint32_t>(compressed.size()),
                               static_cast<uint32_t>(columns.size())};
    file.append(reinterpret_cast<const char*>(sizes), sizeof sizes);
    file.append(reinterpret_cast<const char*>(compressed.data()), compressed.size());
  } else {
    std::string rows;
    rows.reserve(packed.num_points * packed.fields.size() * 12);
    for (size_t p = 0; p < packed.num_points; ++p) {
      const uint8_t* record = packed.data.data() + p * packed.point_step;
      for (size_t k = 0; k < packed.fields.size(); ++k) {
        if (k > 0) rows.push_back(' ');
        append_ascii_value(rows, packed.fields[k].type, record + packed.fields[k].offset);
      }
      rows.push_back('\n');
      if (rows.size() > (1 << 20)) {
        file.append(rows.data(), rows.size());
        rows.clear();
      }
    }
    file.append(rows.data(), rows.size());
  }
  file.commit();
}

}  // namespace keel::io
