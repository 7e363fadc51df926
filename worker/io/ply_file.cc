// PLY point clouds (the `vertex` element): ascii and binary_little_endian. Own parser: the
// vertex records of binary PLY are already packed, so they are unpacked in place.
#include <algorithm>
#include <cstring>
#include <string_view>
#include <vector>

#include "worker/io/io_error.h"
#include "worker/io/scan_file.h"
#include "worker/io/text_lines.h"
#include "worker/io/text_writer.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

bool ply_type(std::string_view name, FieldType& type) {
  static const std::pair<const char*, FieldType> kTypes[] = {
      {"char", FieldType::kInt8},      {"int8", FieldType::kInt8},
      {"uchar", FieldType::kUint8},    {"uint8", FieldType::kUint8},
      {"short", FieldType::kInt16},    {"int16", FieldType::kInt16},
      {"ushort", FieldType::kUint16},  {"uint16", FieldType::kUint16},
      {"int", FieldType::kInt32},      {"int32", FieldType::kInt32},
      {"uint", FieldType::kUint32},    {"uint32", FieldType::kUint32},
      {"float", FieldType::kFloat32},  {"float32", FieldType::kFloat32},
      {"double", FieldType::kFloat64}, {"float64", FieldType::kFloat64}};
  for (const auto& [n, t] : kTypes)
    if (name == n) {
      type = t;
      return true;
    }
  return false;
}

const char* ply_name(FieldType type) {
  switch (type) {
    case FieldType::kInt8:
      return "char";
    case FieldType::kUint8:
      return "uchar";
    case FieldType::kInt16:
      return "short";
    case FieldType::kUint16:
      return "ushort";
    case FieldType::kInt32:
      return "int";
    case FieldType::kUint32:
      return "uint";
    case FieldType::kFloat32:
      return "float";
    case FieldType::kFloat64:
      return "double";
    default:
      return nullptr;  // PLY has no 64-bit integers
  }
}

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// A property of an element after the vertices (faces, edges, ...): read only to be skipped.
struct PlyOtherProperty {
  FieldType type = FieldType::kUint8;  // item type for lists
  bool is_list = false;
  FieldType count_type = FieldType::kUint8;
};

struct PlyOtherElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyOtherProperty> properties;
};

struct PlyHeader {
  bool ascii = false;
  size_t num_vertices = 0;
  size_t point_step = 0;
  std::vector<PackedField> fields;
  std::vector<PlyOtherElement> others;  // elements after the vertices, in file order
  size_t body_offset = 0;               // byte offset of the first vertex
  size_t header_lines = 0;
};

// What the header declares, for messages: "element vertex 3, element face 1".
std::string declared_elements(const PlyHeader& h) {
  std::string out = "element vertex " + std::to_string(h.num_vertices);
  for (const auto& e : h.others) out += ", element " + e.name + " " + std::to_string(e.count);
  return out;
}

PlyOtherProperty parse_other_property(const std::vector<std::string_view>& w,
                                      const std::string& file, size_t line) {
  auto fail = [&](const std::string& message) {
    return IoError(file + ":" + std::to_string(line) + ": " + message);
  };
  PlyOtherProperty property;
  if (w.size() == 5 && w[1] == "list") {
    property.is_list = true;
    if (!ply_type(w[2], property.count_type) || !ply_type(w[3], property.type))
      throw fail("malformed list property line");
    if (!is_integer(property.count_type)) throw fail("list count type must be an integer type");
  } else if (w.size() != 3 || !ply_type(w[1], property.type)) {
    throw fail("malformed property line");
  }
  return property;
}

PlyHeader parse_header(const std::string& bytes, const std::string& file) {
  auto fail = [&](size_t line, const std::string& message) -> IoError {
    return IoError(file + ":" + std::to_string(line) + ": " + message);
  };
  PlyHeader h;
  size_t position = 0, line_number = 0;
  enum { kBeforeVertex, kInVertex, kAfterVertex } state = kBeforeVertex;
  bool format_seen = false;
  while (true) {
    const size_t newline = bytes.find('\n', position);
    if (newline == std::string::npos)
      throw IoError(file + ": malformed PLY: header has no end_header (truncated?)");
    const std::string_view line(bytes.data() + position, newline - position);
    position = newline + 1;
    ++line_number;
    const auto w = words(line);
    if (line_number == 1) {
      if (w.size() != 1 || w[0] != "ply") throw IoError(file + ": not a PLY file (no 'ply' magic)");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") break;
    if (w[0] == "format") {
      if (w.size() != 3) throw fail(line_number, "malformed format line");
      if (w[1] == "ascii")
        h.ascii = true;
      else if (w[1] == "binary_little_endian")
        h.ascii = false;
      else
        throw fail(line_number, "PLY format '" + std::string(w[1]) +
                                    "' not supported (ascii or binary_little_endian)");
      format_seen = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) throw fail(line_number, "malformed element line");
      if (w[1] == "vertex") {
        if (state != kBeforeVertex) throw fail(line_number, "second vertex element");
        int64_t count = 0;
        if (!parse_int64(w[2], count) || count < 0) throw fail(line_number, "bad vertex count");
        h.num_vertices = static_cast<size_t>(count);
        state = kInVertex;
      } else {
        if (state == kBeforeVertex)
          throw fail(line_number, "element '" + std::string(w[1]) +
                                      "' before vertex; a point cloud PLY starts with vertex");
        int64_t count = 0;
        if (!parse_int64(w[2], count) || count < 0)
          throw fail(line_number, "bad count of element '" + std::string(w[1]) + "'");
        h.others.push_back({std::string(w[1]), static_cast<size_t>(count), {}});
        state = kAfterVertex;
      }
    } else if (w[0] == "property") {
      if (state == kAfterVertex) {  // later elements (faces) are skipped, but must be sized
        h.others.back().properties.push_back(parse_other_property(w, file, line_number));
        continue;
      }
      if (state != kInVertex) throw fail(line_number, "property before any element");
      if (w.size() >= 2 && w[1] == "list")
        throw fail(line_number, "list property in the vertex element is not supported");
      FieldType type;
      if (w.size() != 3 || !ply_type(w[1], type))
        throw fail(line_number, "malformed property line");
      h.fields.push_back({std::string(w[2]), type, h.point_step, 1});
      h.point_step += field_size(type);
    } else {
      throw fail(line_number, "unknown header keyword '" + std::string(w[0]) + "'");
    }
  }
  if (!format_seen) throw IoError(file + ": malformed PLY: no format line");
  if (state == kBeforeVertex) throw IoError(file + ": PLY has no vertex element");
  h.body_offset = position;
  h.header_lines = line_number;
  return h;
}

// Parses `count` ascii vertex lines into packed records; `position` and `line_number` end
// after the last vertex line.
std::vector<uint8_t> parse_ascii_body(const std::string& bytes, const PlyHeader& h,
                                      const std::string& file, size_t& position,
                                      size_t& line_number) {
  std::vector<uint8_t> data(h.num_vertices * h.point_step);
  position = h.body_offset;
  line_number = h.header_lines;
  for (size_t i = 0; i < h.num_vertices; ++i) {
    ++line_number;
    if (position >= bytes.size())
      throw IoError(file + ": truncated PLY: expected " + std::to_string(h.num_vertices) +
                    " vertices, found " + std::to_string(i));
    size_t newline = bytes.find('\n', position);
    if (newline == std::string::npos) newline = bytes.size();
    const auto w = words(std::string_view(bytes.data() + position, newline - position));
    position = newline + 1;
    if (w.size() < h.fields.size())
      throw IoError(file + ":" + std::to_string(line_number) + ": expected " +
                    std::to_string(h.fields.size()) + " vertex values, found " +
                    std::to_string(w.size()) + (position >= bytes.size() ? " (truncated?)" : ""));
    if (w.size() > h.fields.size())
      throw IoError(file + ":" + std::to_string(line_number) + ": expected " +
                    std::to_string(h.fields.size()) + " vertex values, found " +
                    std::to_string(w.size()) + " (header and data disagree)");
    uint8_t* record = data.data() + i * h.point_step;
    for (size_t f = 0; f < h.fields.size(); ++f) {
      const PackedField& field = h.fields[f];
      double value = 0;
      if (!parse_double(w[f], value))
        throw IoError(file + ":" + std::to_string(line_number) + ": property '" + field.name +
                      "': expected a number, got '" + std::string(w[f]) + "'");
      uint8_t* p = record + field.offset;
      switch (field.type) {
        case FieldType::kInt8: {
          int8_t v = static_cast<int8_t>(value);
          std::memcpy(p, &v, 1);
          break;
        }
        case FieldType::kUint8: {
          uint8_t v = static_cast<uint8_t>(value);
          std::memcpy(p, &v, 1);
          break;
        }
        case FieldType::kInt16: {
          int16_t v = static_cast<int16_t>(value);
          std::memcpy(p, &v, 2);
          break;
        }
        case FieldType::kUint16: {
          uint16_t v = static_cast<uint16_t>(value);
          std::memcpy(p, &v, 2);
          break;
        }
        case FieldType::kInt32: {
          int32_t v = static_cast<int32_t>(value);
          std::memcpy(p, &v, 4);
          break;
        }
        case FieldType::kUint32: {
          uint32_t v = static_cast<uint32_t>(value);
          std::memcpy(p, &v, 4);
          break;
        }
        case FieldType::kFloat32: {
          float v = static_cast<float>(value);
          std::memcpy(p, &v, 4);
          break;
        }
        case FieldType::kFloat64:
          std::memcpy(p, &value, 8);
          break;
        default:
          break;
      }
    }
  }
  return data;
}

// The next line holding a value, advancing `position` and `line_number`; false at the end.
bool next_content_line(const std::string& bytes, size_t& position, size_t& line_number) {
  while (position < bytes.size()) {
    size_t newline = bytes.find('\n', position);
    if (newline == std::string::npos) newline = bytes.size();
    const std::string_view line(bytes.data() + position, newline - position);
    position = newline + 1;
    ++line_number;
    if (!words(line).empty()) return true;
  }
  return false;
}

// Skips the elements after the vertices (one line per item), then requires the rest of the
// file to be blank: data the header does not declare means header and data disagree.
void check_ascii_rest(const std::string& bytes, const PlyHeader& h, const std::string& file,
                      size_t position, size_t line_number) {
  for (const auto& element : h.others)
    for (size_t i = 0; i < element.count; ++i)
      if (!next_content_line(bytes, position, line_number))
        throw IoError(file + ": truncated PLY: element '" + element.name + "' declares " +
                      std::to_string(element.count) + " items, found " + std::to_string(i));
  size_t extra_lines = 0, first_extra_line = 0;
  while (next_content_line(bytes, position, line_number))
    if (extra_lines++ == 0) first_extra_line = line_number;
  if (extra_lines > 0)
    throw IoError(file + ":" + std::to_string(first_extra_line) + ": " +
                  std::to_string(extra_lines) +
                  " data lines left over after every element the header declares (" +
                  declared_elements(h) + ")");
}

uint64_t read_list_count(const std::string& bytes, size_t offset, FieldType type) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + offset);
  switch (type) {
    case FieldType::kInt8:
    case FieldType::kUint8:
      return p[0];
    case FieldType::kInt16:
    case FieldType::kUint16:
      return static_cast<uint64_t>(p[0]) | static_cast<uint64_t>(p[1]) << 8;
    default:  // 32-bit counts (header parsing allows integer count types only)
      return static_cast<uint64_t>(p[0]) | static_cast<uint64_t>(p[1]) << 8 |
             static_cast<uint64_t>(p[2]) << 16 | static_cast<uint64_t>(p[3]) << 24;
  }
}

// Binary counterpart of check_ascii_rest: walks the elements after the vertices (list
// lengths are read from the data), then requires the file to end there.
void check_binary_rest(const std::string& bytes, const PlyHeader& h, const std::string& file) {
  size_t offset = h.body_offset + h.num_vertices * h.point_step;
  for (const auto& element : h.others) {
    if (element.properties.empty()) continue;  // items of no bytes
    for (size_t i = 0; i < element.count; ++i) {
      for (const auto& property : element.properties) {
        auto need = [&](uint64_t size) {
          if (size > bytes.size() - offset)
            throw IoError(file + ": truncated PLY: element '" + element.name + "' item " +
                          std::to_string(i) + " of " + std::to_string(element.count) +
                          " runs past the end of the file (byte " + std::to_string(offset) +
                          " of " + std::to_string(bytes.size()) + ")");
        };
        uint64_t items = 1;
        if (property.is_list) {
          need(field_size(property.count_type));
          items = read_list_count(bytes, offset, property.count_type);
          offset += field_size(property.count_type);
        }
        need(items * field_size(property.type));
        offset += items * field_size(property.type);
      }
    }
  }
  if (offset < bytes.size())
    throw IoError(file + ": " + std::to_string(bytes.size() - offset) +
                  " bytes left over after every element the header declares (" +
                  declared_elements(h) + ", ending at byte " + std::to_string(offset) + " of " +
                  std::to_string(bytes.size()) + ")");
}

}  // namespace

ScanFileInfo read_ply_info(const fs::path& path) {
  // Headers are small: read the first 64 KiB only.
  const std::string file = path.string();
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError(file + ": cannot open");
  std::string head(1 << 16, '\0');
  head.resize(std::fread(head.data(), 1, head.size(), f.get()));
  const PlyHeader h = parse_header(head, file);
  return {h.num_vertices, h.fields, h.ascii ? "ply ascii" : "ply binary_little_endian"};
}

PointCloud read_ply(const fs::path& path, TimeNs t_ns, const ScanReadOptions& options) {
  const std::string file = path.string();
  const std::string bytes = read_file_bytes(path);
  const PlyHeader h = parse_header(bytes, file);
  const size_t body_bytes = bytes.size() - h.body_offset;
  if (h.ascii) {
    // Every vertex line takes at least one byte: a larger count is a truncated file, refused
    // before allocating records for it.
    if (h.num_vertices > body_bytes)
      throw IoError(file + ": truncated PLY: expected " + std::to_string(h.num_vertices) +
                    " vertices, the body has only " + std::to_string(body_bytes) + " bytes");
    size_t position = 0, line_number = 0;
    const std::vector<uint8_t> data = parse_ascii_body(bytes, h, file, position, line_number);
    check_ascii_rest(bytes, h, file, position, line_number);
    return unpack_cloud({data.data(), h.num_vertices, h.point_step, h.fields}, t_ns, options, file);
  }
  // Divided, not multiplied: a hostile vertex count must not overflow the size.
  if (h.num_vertices > body_bytes / std::max<size_t>(1, h.point_step))
    throw IoError(file + ": truncated PLY: " + std::to_string(h.num_vertices) + " vertices of " +
                  std::to_string(h.point_step) + " bytes need more than the " +
                  std::to_string(body_bytes) + " bytes of data the file has");
  check_binary_rest(bytes, h, file);
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data() + h.body_offset);
  return unpack_cloud({data, h.num_vertices, h.point_step, h.fields}, t_ns, options, file);
}

void write_ply(const fs::path& path, const PointCloud& cloud, const ScanWriteOptions& options) {
  const std::string file = path.string();
  if (options.encoding == ScanEncoding::kBinaryCompressed)
    throw IoError(file + ": PLY has no compressed encoding (ascii or binary)");
  const PackedCloud packed = pack_cloud(cloud, options.time);
  const bool ascii = options.encoding == ScanEncoding::kAscii;
  TextWriter w(path);
  w.text("ply\nformat ").text(ascii ? "ascii" : "binary_little_endian").text(" 1.0\n");
  w.text("element vertex ").integer(static_cast<long long>(packed.num_points)).text("\n");
  for (const auto& f : packed.fields) {
    const char* type = ply_name(f.type);
    if (!type)
      throw IoError(file + ": PLY cannot store field '" + f.name + "' as " + to_string(f.type));
    w.text("property ").text(type).text(" ").text(f.name).text("\n");
  }
  w.text("end_header\n");
  if (!ascii) {
    w.text(std::string_view(reinterpret_cast<const char*>(packed.data.data()), packed.data.size()));
  } else {
    for (size_t i = 0; i < packed.num_points; ++i) {
      for (size_t f = 0; f < packed.fields.size(); ++f) {
        const uint8_t* p = packed.data.data() + i * packed.point_step + packed.fields[f].offset;
        double value = 0;
        switch (packed.fields[f].type) {
          case FieldType::kFloat32: {
            float v;
            std::memcpy(&v, p, 4);
            value = v;
            break;
          }
          case FieldType::kFloat64:
            std::memcpy(&value, p, 8);
            break;
          case FieldType::kUint16: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            value = v;
            break;
          }
          case FieldType::kUint32: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            value = v;
            break;
          }
          case FieldType::kInt32: {
            int32_t v;
            std::memcpy(&v, p, 4);
            value = v;
            break;
          }
          default: {
            uint8_t v;
            std::memcpy(&v, p, 1);
            value = v;
            break;
          }
        }
        w.text(f ? " " : "").number(value);
      }
      w.text("\n");
    }
  }
  w.close();
}

}  // namespace keel::io
