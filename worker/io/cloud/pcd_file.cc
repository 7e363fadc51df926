// PCD through PCL's reader/writer (pcl::PCLPointCloud2), kept out of every header.
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <charconv>
#include <cstdio>
#include <cstring>
#include <string_view>
#include <vector>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/cloud/pcd_header_check.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/text_lines.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

FieldType from_pcl(const pcl::PCLPointField& field, const std::string& file) {
  using T = pcl::PCLPointField;
  switch (field.datatype) {
    case T::INT8:
      return FieldType::kInt8;
    case T::UINT8:
      return FieldType::kUint8;
    case T::INT16:
      return FieldType::kInt16;
    case T::UINT16:
      return FieldType::kUint16;
    case T::INT32:
      return FieldType::kInt32;
    case T::UINT32:
      return FieldType::kUint32;
    case T::INT64:
      return FieldType::kInt64;
    case T::UINT64:
      return FieldType::kUint64;
    case T::FLOAT32:
      return FieldType::kFloat32;
    case T::FLOAT64:
      return FieldType::kFloat64;
    default:
      throw IoError(file + ": field '" + field.name + "' has unsupported PCD type " +
                    std::to_string(field.datatype));
  }
}

uint8_t to_pcl(FieldType type) {
  using T = pcl::PCLPointField;
  switch (type) {
    case FieldType::kInt8:
      return T::INT8;
    case FieldType::kUint8:
      return T::UINT8;
    case FieldType::kInt16:
      return T::INT16;
    case FieldType::kUint16:
      return T::UINT16;
    case FieldType::kInt32:
      return T::INT32;
    case FieldType::kUint32:
      return T::UINT32;
    case FieldType::kInt64:
      return T::INT64;
    case FieldType::kUint64:
      return T::UINT64;
    case FieldType::kFloat32:
      return T::FLOAT32;
    case FieldType::kFloat64:
      return T::FLOAT64;
  }
  return T::FLOAT32;
}

std::vector<PackedField> fields_of(const pcl::PCLPointCloud2& cloud, const std::string& file) {
  std::vector<PackedField> fields;
  for (const auto& f : cloud.fields) {
    if (f.name == "_") continue;  // PCL's padding
    fields.push_back({f.name, from_pcl(f, file), f.offset, std::max<size_t>(1, f.count)});
  }
  return fields;
}

const char* kEncodings[] = {"ascii", "binary", "binary_compressed"};

struct PcdHeader {
  pcl::PCLPointCloud2 cloud;  // fields, width, height, point_step; no data
  int data_type = 0;          // 0 ascii, 1 binary, 2 binary_compressed
  unsigned int data_idx = 0;  // byte offset of the body
};

PcdHeader read_header(const fs::path& path) {
  const std::string file = path.string();
  const std::string name = display_path(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw IoError(name + ": not found");
  // PCL accepts a header cut before its DATA line as an empty cloud: require the line.
  {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
    std::string head(kPcdHeaderBytes, '\0');
    head.resize(f ? std::fread(head.data(), 1, head.size(), f.get()) : 0);
    check_pcd_header(head, fs::file_size(path), name);
  }
  PcdHeader h;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  pcl::PCDReader reader;
  int status = -1;
  try {
    status =
        reader.readHeader(file, h.cloud, origin, orientation, version, h.data_type, h.data_idx);
  } catch (const std::exception&) {
    // PCL indexes a header line's words with vector::at: a keyword alone on its line (a
    // "DATA" with no encoding, found by fuzz_scan_file) throws std::out_of_range.
    status = -1;
  }
  if (status < 0)
    throw IoError(name +
                  ": malformed PCD header (expected VERSION, FIELDS, SIZE, TYPE, COUNT, "
                  "WIDTH, HEIGHT, POINTS, DATA, each with its values)");
  if (h.data_type < 0 || h.data_type > 2) throw IoError(name + ": unknown PCD DATA encoding");
  // PCL accepts a header without FIELDS and then dereferences null reading the body (a SEGV
  // found by fuzz_scan_file).
  if (h.cloud.fields.empty() || h.cloud.point_step == 0)
    throw IoError(name + ": malformed PCD header: no FIELDS (or fields of no size)");
  // check_pcd_header() read the header as PCL should have; where PCL read it otherwise (its
  // parser is looser), its layout must still be the packed one the header describes: every
  // field starting where the ones before it end, the sum in 64 bits.
  uint64_t point_bytes = 0;
  for (const auto& f : h.cloud.fields) {
    if (f.count > kMaxPcdFieldCount)
      throw IoError(name + ": malformed PCD header: field '" + f.name + "' has COUNT " +
                    std::to_string(f.count) + " (at most " + std::to_string(kMaxPcdFieldCount) +
                    " values per field are read)");
    if (f.offset != point_bytes)
      throw IoError(name + ": malformed PCD header: field '" + f.name + "' starts at byte " +
                    std::to_string(f.offset) + " of a point, the SIZE x COUNT of the fields " +
                    "before it end at byte " + std::to_string(point_bytes));
    const uint64_t size = field_size(from_pcl(f, name));
    point_bytes += size * std::max<uint64_t>(1, f.count);
  }
  if (point_bytes != h.cloud.point_step)
    throw IoError(name + ": malformed PCD header: SIZE x COUNT over FIELDS is " +
                  std::to_string(point_bytes) + " bytes a point, PCL computed " +
                  std::to_string(h.cloud.point_step));
  return h;
}

// Binary bodies are checked against the file size here so that a truncated file names the
// bytes missing (PCL's own message is generic).
void check_body_size(const fs::path& path, const PcdHeader& h) {
  const std::string file = path.string();
  const std::string name = display_path(path);
  const uint64_t file_size = fs::file_size(path);
  const uint64_t points = static_cast<uint64_t>(h.cloud.width) * h.cloud.height;
  const uint64_t body = points * h.cloud.point_step;
  if (h.data_type == 1 && h.data_idx + body > file_size)
    throw IoError(name + ": truncated PCD: " + std::to_string(points) + " points of " +
                  std::to_string(h.cloud.point_step) + " bytes need " + std::to_string(body) +
                  " bytes of data, the file has " +
                  std::to_string(file_size - std::min<uint64_t>(file_size, h.data_idx)));
  if (h.data_type == 2) {
    uint32_t sizes[2] = {0, 0};  // compressed, uncompressed
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
    if (!f || std::fseek(f.get(), h.data_idx, SEEK_SET) != 0 ||
        std::fread(sizes, 4, 2, f.get()) != 2)
      throw IoError(name + ": truncated PCD: missing the binary_compressed size header");
    if (h.data_idx + 8ull + sizes[0] > file_size)
      throw IoError(name + ": truncated PCD: compressed body of " + std::to_string(sizes[0]) +
                    " bytes, the file has " + std::to_string(file_size - h.data_idx - 8));
    if (sizes[1] != body)
      throw IoError(name + ": malformed PCD: compressed body unpacks to " +
                    std::to_string(sizes[1]) + " bytes, the header needs " + std::to_string(body));
    // LZF copies at most 264 bytes for a 3-byte back reference: a body claiming more than 88
    // times its compressed size is not LZF (and PCL would allocate the claim first).
    if (sizes[1] > 88ull * sizes[0] + 8)
      throw IoError(name + ": malformed PCD: a compressed body of " + std::to_string(sizes[0]) +
                    " bytes cannot unpack to " + std::to_string(sizes[1]) +
                    " (LZF expands at most 88 times)");
  }
}

// PCL reads a short or long ascii row as a point at the origin (with only a warning), a
// non-number as 0, and ignores rows beyond POINTS: check every row before PCL reads them.
// Rows hold the sum of COUNT over FIELDS values, padding fields ('_') included, as in PCL.
void check_ascii_body(const fs::path& path, const PcdHeader& h) {
  const std::string file = path.string();
  const std::string name = display_path(path);
  TextLines lines(path);
  size_t values_per_row = 0;
  for (const auto& f : h.cloud.fields) values_per_row += f.count;
  const uint64_t points = static_cast<uint64_t>(h.cloud.width) * h.cloud.height;
  std::string_view line;
  std::vector<std::string_view> tokens;
  while (lines.next(line)) {  // the header ends with its DATA line
    mesh_detail::split_whitespace(line, &tokens);
    if (!tokens.empty() && tokens[0] == "DATA") break;
  }
  uint64_t rows = 0;
  size_t first_extra_line = 0;
  while (lines.next(line)) {
    mesh_detail::split_whitespace(line, &tokens);
    if (tokens.empty()) continue;  // blank lines hold no point (PCL skips them too)
    if (++rows > points) {
      if (first_extra_line == 0) first_extra_line = lines.line_number();
      continue;
    }
    const std::string where = name + ":" + std::to_string(lines.line_number()) + ": data row " +
                              std::to_string(rows) + ": ";
    if (tokens.size() != values_per_row)
      throw IoError(where + "expected " + std::to_string(values_per_row) +
                    " values (the sum of COUNT over FIELDS), found " +
                    std::to_string(tokens.size()));
    for (const std::string_view token : tokens) {
      double value = 0;
      if (!parse_double(token, value))
        throw IoError(where + "expected a number, got '" + std::string(token) + "'");
    }
  }
  if (rows < points)
    throw IoError(name + ": truncated PCD: POINTS declares " + std::to_string(points) +
                  " points, the ascii body has " + std::to_string(rows) + " rows");
  if (rows > points)
    throw IoError(name + ":" + std::to_string(first_extra_line) + ": " +
                  std::to_string(rows - points) + " data rows beyond the " +
                  std::to_string(points) + " points the header declares (POINTS " +
                  std::to_string(points) + ")");
}

}  // namespace

ScanFileInfo read_pcd_info(const fs::path& path) {
  const PcdHeader h = read_header(path);
  ScanFileInfo info;
  info.num_points = static_cast<size_t>(h.cloud.width) * h.cloud.height;
  info.fields = fields_of(h.cloud, display_path(path));
  info.format = std::string("pcd ") + kEncodings[h.data_type];
  return info;
}

PointCloud read_pcd(const fs::path& path, TimeNs t_ns, const ScanReadOptions& options) {
  const std::string file = path.string();
  const std::string name = display_path(path);
  const PcdHeader h = read_header(path);
  check_body_size(path, h);
  if (h.data_type == 0) check_ascii_body(path, h);
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  int status = -1;
  try {
    status = reader.read(file, cloud);
  } catch (const std::exception&) {
    status = -1;  // PCL's vector::at on a malformed line, as in read_header
  }
  if (status < 0)
    throw IoError(name + ": malformed or truncated PCD " + kEncodings[h.data_type] + " body (" +
                  std::to_string(static_cast<uint64_t>(h.cloud.width) * h.cloud.height) +
                  " points expected)");
  const size_t points = static_cast<size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() < points * cloud.point_step)
    throw IoError(name + ": truncated PCD: fewer data bytes than " + std::to_string(points) +
                  " points");
  PackedCloudView view{cloud.data.data(), points, cloud.point_step, fields_of(cloud, name)};
  return unpack_cloud(view, t_ns, options, name);
}

void write_pcd(const fs::path& path, const PointCloud& cloud, const ScanWriteOptions& options) {
  const PackedCloud packed = pack_cloud(cloud, options.time);
  pcl::PCLPointCloud2 out;
  out.width = static_cast<uint32_t>(packed.num_points);
  out.height = 1;
  out.point_step = static_cast<uint32_t>(packed.point_step);
  out.row_step = out.point_step * out.width;
  out.is_dense = false;
  for (const auto& f : packed.fields) {
    pcl::PCLPointField field;
    field.name = f.name;
    field.offset = static_cast<uint32_t>(f.offset);
    field.datatype = to_pcl(f.type);
    field.count = 1;
    out.fields.push_back(field);
  }
  out.data = packed.data;
  pcl::PCDWriter writer;
  const std::string file = path.string();
  int result = 0;
  switch (options.encoding) {
    case ScanEncoding::kAscii:
      result =
          writer.writeASCII(file, out, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(), 17);
      break;
    case ScanEncoding::kBinary:
      result = writer.writeBinary(file, out);
      break;
    case ScanEncoding::kBinaryCompressed:
      result = writer.writeBinaryCompressed(file, out);
      break;
  }
  if (result < 0) throw IoError(file + ": cannot write PCD");
}

}  // namespace keel::io
