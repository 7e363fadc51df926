// PLY point clouds (the `vertex` element): ascii and binary_little_endian. The header is
// parsed by ply_header.h; the vertex records of binary PLY are already packed, so they are
// unpacked in place.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

#include "core/replaced_file.h"
#include "worker/io/cloud/ply_header.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/mapped_file.h"
#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/text_lines.h"
#include "worker/io/text_writer.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

FieldType field_type(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
      return FieldType::kInt8;
    case PlyType::kUint8:
      return FieldType::kUint8;
    case PlyType::kInt16:
      return FieldType::kInt16;
    case PlyType::kUint16:
      return FieldType::kUint16;
    case PlyType::kInt32:
      return FieldType::kInt32;
    case PlyType::kUint32:
      return FieldType::kUint32;
    case PlyType::kFloat32:
      return FieldType::kFloat32;
    case PlyType::kFloat64:
      return FieldType::kFloat64;
  }
  return FieldType::kFloat64;
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

// The header, and its vertex element as packed records (the elements after it, faces or
// edges, are only skipped).
struct PlyCloudLayout {
  PlyHeader header;
  size_t num_vertices = 0;
  size_t point_step = 0;
  std::vector<PackedField> fields;
};

// What the header declares, for messages: "element vertex 3, element face 1".
std::string declared_elements(const PlyHeader& h) {
  std::string out;
  for (const auto& e : h.elements)
    out += (out.empty() ? "element " : ", element ") + e.name + " " + std::to_string(e.count);
  return out;
}

// What a point cloud needs on top of a valid PLY header: little endian or ascii, and one
// vertex element, first, of scalar properties.
PlyCloudLayout parse_layout(std::string_view bytes, const std::string& file) {
  auto fail = [&](size_t line, const std::string& message) {
    return IoError(file + ":" + std::to_string(line) + ": " + message);
  };
  PlyCloudLayout layout;
  layout.header = parse_ply_header(bytes, file);
  const PlyHeader& h = layout.header;
  if (h.format == PlyFormat::kBinaryBigEndian)
    throw fail(h.format_line, std::string("PLY format '") + to_string(h.format) +
                                  "' not supported (ascii or binary_little_endian)");
  if (h.elements.empty()) throw IoError(file + ": PLY has no vertex element");
  for (size_t i = 0; i < h.elements.size(); ++i) {
    const PlyElement& e = h.elements[i];
    if (i == 0 && e.name != "vertex")
      throw fail(e.line,
                 "element '" + e.name + "' before vertex; a point cloud PLY starts with vertex");
    if (i > 0 && e.name == "vertex") throw fail(e.line, "second vertex element");
  }
  const PlyElement& vertex = h.elements.front();
  layout.num_vertices = vertex.count;
  for (const auto& property : vertex.properties) {
    if (property.is_list)
      throw fail(property.line, "list property in the vertex element is not supported");
    const FieldType type = field_type(property.type);
    layout.fields.push_back({property.name, type, layout.point_step, 1});
    layout.point_step += field_size(type);
  }
  return layout;
}

template <typename T>
bool in_range(double value) {  // false for NaN too
  return value >= static_cast<double>(std::numeric_limits<T>::lowest()) &&
         value <= static_cast<double>(std::numeric_limits<T>::max());
}

// Whether an ascii value converts to its property's type: NaN or an out-of-range value into
// an integer, or a finite double beyond float's range into a float, is undefined behaviour
// (fuzz_scan_file: 'nan' for a uchar property).
bool representable(FieldType type, double value) {
  switch (type) {
    case FieldType::kInt8:
      return in_range<int8_t>(value);
    case FieldType::kUint8:
      return in_range<uint8_t>(value);
    case FieldType::kInt16:
      return in_range<int16_t>(value);
    case FieldType::kUint16:
      return in_range<uint16_t>(value);
    case FieldType::kInt32:
      return in_range<int32_t>(value);
    case FieldType::kUint32:
      return in_range<uint32_t>(value);
    case FieldType::kFloat32:
      return !std::isfinite(value) || in_range<float>(value);
    default:
      return true;
  }
}

// Parses `count` ascii vertex lines into packed records; `position` and `line_number` end
// after the last vertex line.
std::vector<uint8_t> parse_ascii_body(std::string_view bytes, const PlyCloudLayout& h,
                                      const std::string& file, size_t& position,
                                      size_t& line_number) {
  std::vector<uint8_t> data(h.num_vertices * h.point_step);
  position = h.header.body_offset;
  line_number = h.header.end_header_line;
  for (size_t i = 0; i < h.num_vertices; ++i) {
    ++line_number;
    if (position >= bytes.size())
      throw IoError(file + ": truncated PLY: expected " + std::to_string(h.num_vertices) +
                    " vertices, found " + std::to_string(i));
    size_t newline = bytes.find('\n', position);
    if (newline == std::string_view::npos) newline = bytes.size();
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
      if (!representable(field.type, value))
        throw IoError(file + ":" + std::to_string(line_number) + ": property '" + field.name +
                      "': '" + std::string(w[f]) + "' is not a " + to_string(field.type) +
                      " value");
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

// Skips the elements after the vertices (one line per item), then requires the rest of the
// file to be blank: data the header does not declare means header and data disagree.
void check_ascii_rest(std::string_view bytes, const PlyHeader& h, const std::string& file,
                      size_t position, size_t line_number) {
  // position is one past the end when the last vertex line has no newline.
  mesh_detail::LineCursor lines(std::string_view(bytes).substr(std::min(position, bytes.size())),
                                line_number + 1);
  std::string_view line;
  for (size_t e = 1; e < h.elements.size(); ++e) {
    const PlyElement& element = h.elements[e];
    for (size_t i = 0; i < element.count; ++i)
      if (!lines.next_content(&line, '\0'))
        throw IoError(file + ": truncated PLY: element '" + element.name + "' declares " +
                      std::to_string(element.count) + " items, found " + std::to_string(i));
  }
  size_t extra_lines = 0, first_extra_line = 0;
  while (lines.next_content(&line, '\0'))
    if (extra_lines++ == 0) first_extra_line = lines.line_number();
  if (extra_lines > 0)
    throw IoError(file + ":" + std::to_string(first_extra_line) + ": " +
                  std::to_string(extra_lines) +
                  " data lines left over after every element the header declares (" +
                  declared_elements(h) + ")");
}

uint64_t read_list_count(std::string_view bytes, size_t offset, PlyType type) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + offset);
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return p[0];
    case PlyType::kInt16:
    case PlyType::kUint16:
      return static_cast<uint64_t>(p[0]) | static_cast<uint64_t>(p[1]) << 8;
    default:  // 32-bit counts (header parsing allows integer count types only)
      return static_cast<uint64_t>(p[0]) | static_cast<uint64_t>(p[1]) << 8 |
             static_cast<uint64_t>(p[2]) << 16 | static_cast<uint64_t>(p[3]) << 24;
  }
}

// Binary counterpart of check_ascii_rest: walks the elements after the vertices (list
// lengths are read from the data), then requires the file to end there.
void check_binary_rest(std::string_view bytes, const PlyCloudLayout& layout,
                       const std::string& file) {
  const PlyHeader& h = layout.header;
  size_t offset = h.body_offset + layout.num_vertices * layout.point_step;
  for (size_t e = 1; e < h.elements.size(); ++e) {
    const PlyElement& element = h.elements[e];
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
          need(ply_type_size(property.count_type));
          items = read_list_count(bytes, offset, property.count_type);
          offset += ply_type_size(property.count_type);
        }
        need(items * ply_type_size(property.type));
        offset += items * ply_type_size(property.type);
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
  const std::string name = display_path(path);
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError(name + ": cannot open");
  std::string head(1 << 16, '\0');
  head.resize(std::fread(head.data(), 1, head.size(), f.get()));
  const PlyCloudLayout h = parse_layout(head, name);
  return {h.num_vertices, h.fields, std::string("ply ") + to_string(h.header.format)};
}

PointCloud read_ply(const fs::path& path, TimeNs t_ns, const ScanReadOptions& options) {
  const std::string file = display_path(path);
  const MappedFile mapped(path);
  const std::string_view bytes = mapped.bytes();
  const PlyCloudLayout h = parse_layout(bytes, file);
  const size_t body_bytes = bytes.size() - h.header.body_offset;
  if (h.header.format == PlyFormat::kAscii) {
    // Every vertex line takes at least one byte: a larger count is a truncated file, refused
    // before allocating records for it.
    if (h.num_vertices > body_bytes)
      throw IoError(file + ": truncated PLY: expected " + std::to_string(h.num_vertices) +
                    " vertices, the body has only " + std::to_string(body_bytes) + " bytes");
    size_t position = 0, line_number = 0;
    const std::vector<uint8_t> data = parse_ascii_body(bytes, h, file, position, line_number);
    check_ascii_rest(bytes, h.header, file, position, line_number);
    return unpack_cloud({data.data(), h.num_vertices, h.point_step, h.fields}, t_ns, options, file);
  }
  // Divided, not multiplied: a hostile vertex count must not overflow the size.
  if (h.num_vertices > body_bytes / std::max<size_t>(1, h.point_step))
    throw IoError(file + ": truncated PLY: " + std::to_string(h.num_vertices) + " vertices of " +
                  std::to_string(h.point_step) + " bytes need more than the " +
                  std::to_string(body_bytes) + " bytes of data the file has");
  check_binary_rest(bytes, h, file);
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data() + h.header.body_offset);
  return unpack_cloud({data, h.num_vertices, h.point_step, h.fields}, t_ns, options, file);
}

void write_ply(const fs::path& path, const PointCloud& cloud, const ScanWriteOptions& options) {
  const std::string file = path.string();
  if (options.encoding == ScanEncoding::kBinaryCompressed)
    throw IoError(file + ": PLY has no compressed encoding (ascii or binary)");
  const PackedCloud packed = pack_cloud(cloud, options.time);
  const bool ascii = options.encoding == ScanEncoding::kAscii;
  std::string header = std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
                       " 1.0\nelement vertex " + std::to_string(packed.num_points) + "\n";
  for (const auto& f : packed.fields) {
    const char* type = ply_name(f.type);
    if (!type)
      throw IoError(file + ": PLY cannot store field '" + f.name + "' as " + to_string(f.type));
    header += std::string("property ") + type + " " + f.name + "\n";
  }
  header += "end_header\n";
  if (!ascii) {  // the packed records are the body: one write
    ReplacedFile out(path);
    out.append(header.data(), header.size());
    out.append(reinterpret_cast<const char*>(packed.data.data()), packed.data.size());
    out.commit();
    return;
  }
  TextWriter w(path);
  w.text(header);
  {
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
