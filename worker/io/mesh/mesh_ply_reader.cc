// PLY mesh reader (ascii, binary little and big endian). See mesh_reader.h.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/cloud/ply_header.h"

namespace keel::io {
namespace {

using mesh_detail::fail;
using mesh_detail::quoted;

// The shared header parser throws IoError; this reader's callers expect MeshReadError.
PlyHeader parse_header(const std::filesystem::path& path, std::string_view text) {
  try {
    return parse_ply_header(text, display_path(path));
  } catch (const IoError& e) {
    throw MeshReadError(e.what());
  }
}

// Reads values of one element item at a time from an ascii body: one item per line.
class AsciiSource {
 public:
  AsciiSource(const std::filesystem::path& path, std::string_view body, size_t first_line)
      : path_(path), lines_(body, first_line) {}

  void begin_item(const PlyElement& element, uint64_t index) {
    std::string_view line;
    if (!lines_.next_content(&line, '\0')) {
      fail(path_, lines_.line_number(),
           "truncated: element '" + element.name + "' declares " + std::to_string(element.count) +
               " items, the file ends after " + std::to_string(index));
    }
    mesh_detail::split_whitespace(line, &tokens_);
    next_token_ = 0;
  }
  double value(PlyType /*type*/, const std::string& property) {
    if (next_token_ >= tokens_.size()) {
      fail(path_, lines_.line_number(), "too few values: missing property '" + property + "'");
    }
    const std::string_view token = tokens_[next_token_++];
    double v = 0;
    if (!mesh_detail::parse_double(token, &v)) {
      fail(path_, lines_.line_number(),
           "property '" + property + "': expected a number, got " + quoted(token));
    }
    return v;
  }
  void end_item() {
    if (next_token_ != tokens_.size()) {
      fail(path_, lines_.line_number(),
           "expected " + std::to_string(next_token_) + " values, got " +
               std::to_string(tokens_.size()) + " (header and data disagree)");
    }
  }
  size_t line() const { return lines_.line_number(); }
  std::string where() const { return ""; }
  uint64_t max_list_length() const { return tokens_.size(); }
  // After every declared element only blank lines may follow.
  void finish() {
    std::string_view line;
    if (lines_.next_content(&line, '\0'))
      fail(path_, lines_.line_number(), "data left over after every element the header declares");
  }

 private:
  const std::filesystem::path& path_;
  mesh_detail::LineCursor lines_;
  std::vector<std::string_view> tokens_;
  size_t next_token_ = 0;
};

// Reads values from a binary body, checking every read against the end of the file.
class BinarySource {
 public:
  BinarySource(const std::filesystem::path& path, std::string_view body, size_t body_offset,
               bool big_endian)
      : path_(path), body_(body), body_offset_(body_offset), big_endian_(big_endian) {}

  void begin_item(const PlyElement& element, uint64_t index) {
    element_ = &element;
    index_ = index;
  }
  double value(PlyType type, const std::string& property) {
    const size_t size = ply_type_size(type);
    if (offset_ + size > body_.size()) {
      fail(path_, 0,
           "truncated binary data: element '" + element_->name + "' item " +
               std::to_string(index_) + " of " + std::to_string(element_->count) + ", property '" +
               property + "' at byte " + std::to_string(body_offset_ + offset_));
    }
    unsigned char bytes[8];
    std::memcpy(bytes, body_.data() + offset_, size);
    offset_ += size;
    if (big_endian_) std::reverse(bytes, bytes + size);  // Keel runs on little-endian hosts.
    return decode(type, bytes);
  }
  void end_item() {}
  size_t line() const { return 0; }
  std::string where() const {
    return " (element '" + element_->name + "' item " + std::to_string(index_) + ", byte " +
           std::to_string(body_offset_ + offset_) + ")";
  }
  // A list cannot be longer than the bytes left in the file.
  uint64_t max_list_length() const { return body_.size() - offset_; }
  // After every declared element the file must end.
  void finish() const {
    if (offset_ != body_.size())
      fail(path_, 0,
           std::to_string(body_.size() - offset_) +
               " bytes left over after every element the header declares (from byte " +
               std::to_string(body_offset_ + offset_) + ")");
  }

 private:
  static double decode(PlyType type, const unsigned char* b) {
    switch (type) {
      case PlyType::kInt8:
        return static_cast<int8_t>(b[0]);
      case PlyType::kUint8:
        return b[0];
      case PlyType::kInt16:
        return load<int16_t>(b);
      case PlyType::kUint16:
        return load<uint16_t>(b);
      case PlyType::kInt32:
        return load<int32_t>(b);
      case PlyType::kUint32:
        return load<uint32_t>(b);
      case PlyType::kFloat32:
        return load<float>(b);
      case PlyType::kFloat64:
        return load<double>(b);
    }
    return 0;
  }
  template <typename T>
  static T load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

  const std::filesystem::path& path_;
  std::string_view body_;
  size_t body_offset_;
  bool big_endian_;
  size_t offset_ = 0;
  const PlyElement* element_ = nullptr;
  uint64_t index_ = 0;
};

int find_property(const PlyElement& element, std::initializer_list<const char*> names) {
  for (size_t i = 0; i < element.properties.size(); ++i) {
    for (const char* name : names) {
      if (element.properties[i].name == name) return static_cast<int>(i);
    }
  }
  return -1;
}

// Where the vertex and face data sit among an element's properties.
struct VertexLayout {
  int x = -1, y = -1, z = -1;
  int nx = -1, ny = -1, nz = -1;
  int red = -1, green = -1, blue = -1;
  bool has_normals() const { return nx >= 0 && ny >= 0 && nz >= 0; }
  bool has_colors() const { return red >= 0 && green >= 0 && blue >= 0; }
};

VertexLayout vertex_layout(const std::filesystem::path& path, const PlyElement& vertex) {
  VertexLayout layout;
  layout.x = find_property(vertex, {"x"});
  layout.y = find_property(vertex, {"y"});
  layout.z = find_property(vertex, {"z"});
  if (layout.x < 0 || layout.y < 0 || layout.z < 0) {
    fail(path, 0, "PLY element 'vertex' has no x, y and z properties");
  }
  for (const int index : {layout.x, layout.y, layout.z}) {
    if (vertex.properties[index].is_list) fail(path, 0, "PLY vertex x/y/z must not be lists");
  }
  layout.nx = find_property(vertex, {"nx"});
  layout.ny = find_property(vertex, {"ny"});
  layout.nz = find_property(vertex, {"nz"});
  layout.red = find_property(vertex, {"red", "r"});
  layout.green = find_property(vertex, {"green", "g"});
  layout.blue = find_property(vertex, {"blue", "b"});
  return layout;
}

// Integral values without a fraction ("8", not "8.000000"), for messages.
std::string number(double value) {
  if (value == std::floor(value) && std::abs(value) < 1e15) {
    return std::to_string(static_cast<long long>(value));
  }
  return std::to_string(value);
}

uint8_t to_color_byte(double value, PlyType type) {
  // Colours stored as floats are in [0, 1]; integer colours in [0, 255].
  const double scaled = ply_type_is_integer(type) ? value : value * 255.0;
  return static_cast<uint8_t>(std::clamp(std::lround(scaled), 0L, 255L));
}

template <typename Source>
void read_body(const std::filesystem::path& path, const PlyHeader& header, Source& source,
               size_t body_bytes, TriangleMesh* mesh) {
  const PlyElement* vertex = nullptr;
  for (const auto& element : header.elements) {
    if (element.name == "vertex") vertex = &element;
  }
  if (vertex == nullptr) fail(path, 0, "PLY file has no 'vertex' element");
  const VertexLayout layout = vertex_layout(path, *vertex);
  const uint64_t num_vertices = vertex->count;
  if (num_vertices > static_cast<uint64_t>(std::numeric_limits<int>::max())) {
    fail(path, 0, "PLY declares " + std::to_string(num_vertices) + " vertices (too many)");
  }

  std::vector<double> scalars;
  std::vector<std::vector<double>> lists;
  std::vector<int> polygon;
  for (const auto& element : header.elements) {
    const bool is_vertex = &element == vertex;
    const int face_list =
        element.name == "face" ? find_property(element, {"vertex_indices", "vertex_index"}) : -1;
    if (element.name == "face" && face_list < 0) {
      fail(path, 0, "PLY element 'face' has no 'vertex_indices' list");
    }
    // A binary element without properties takes no bytes, however many items it declares:
    // walking its count would only spin (2^63 items).
    if (element.properties.empty() && header.format != PlyFormat::kAscii) continue;
    // Never trust a declared count for an allocation: cap it by the file size.
    const uint64_t reserve = std::min<uint64_t>(element.count, body_bytes / 2);
    if (is_vertex) {
      mesh->vertices.reserve(reserve);
      if (layout.has_normals()) mesh->vertex_normals.reserve(reserve);
      if (layout.has_colors()) mesh->vertex_colors.reserve(reserve);
    }
    scalars.assign(element.properties.size(), 0.0);
    lists.resize(element.properties.size());
    for (uint64_t item = 0; item < element.count; ++item) {
      source.begin_item(element, item);
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          scalars[p] = source.value(property.type, property.name);
          continue;
        }
        const double count = source.value(property.count_type, property.name + " count");
        if (count < 0 || count != std::floor(count) ||
            count > static_cast<double>(source.max_list_length())) {
          fail(path, source.line(),
               "list '" + property.name + "' has an impossible length " + number(count) +
                   source.where());
        }
        lists[p].resize(static_cast<size_t>(count));
        for (auto& v : lists[p]) v = source.value(property.type, property.name);
      }
      source.end_item();

      if (is_vertex) {
        const Eigen::Vector3d p(scalars[layout.x], scalars[layout.y], scalars[layout.z]);
        if (!mesh_detail::is_finite(p)) {
          fail(path, source.line(),
               "vertex " + std::to_string(item) + " has a non-finite coordinate (NaN or inf)" +
                   source.where());
        }
        mesh->vertices.push_back(p);
        if (layout.has_normals()) {
          mesh->vertex_normals.emplace_back(scalars[layout.nx], scalars[layout.ny],
                                            scalars[layout.nz]);
        }
        if (layout.has_colors()) {
          mesh->vertex_colors.emplace_back(
              to_color_byte(scalars[layout.red], element.properties[layout.red].type),
              to_color_byte(scalars[layout.green], element.properties[layout.green].type),
              to_color_byte(scalars[layout.blue], element.properties[layout.blue].type));
        }
      } else if (face_list >= 0) {
        const auto& indices = lists[face_list];
        if (indices.size() < 3) {
          fail(path, source.line(),
               "face " + std::to_string(item) + " has " + std::to_string(indices.size()) +
                   " vertices (expected at least 3)" + source.where());
        }
        polygon.clear();
        for (const double index : indices) {
          if (index < 0 || index >= static_cast<double>(num_vertices) ||
              index != std::floor(index)) {
            fail(path, source.line(),
                 "face " + std::to_string(item) + ": vertex index " + number(index) +
                     " out of range (the file has " + std::to_string(num_vertices) + " vertices)" +
                     source.where());
          }
          polygon.push_back(static_cast<int>(index));
        }
        mesh_detail::add_polygon_fan(polygon, &mesh->faces);
      }
    }
  }
}

}  // namespace

TriangleMesh read_ply_mesh(const std::filesystem::path& path) {
  const std::string text = mesh_detail::read_file_bytes(path);
  const PlyHeader header = parse_header(path, text);
  const std::string_view body = std::string_view(text).substr(header.body_offset);
  TriangleMesh mesh;
  if (header.format == PlyFormat::kAscii) {
    AsciiSource source(path, body, header.end_header_line + 1);
    read_body(path, header, source, body.size(), &mesh);
    source.finish();
  } else {
    BinarySource source(path, body, header.body_offset,
                        header.format == PlyFormat::kBinaryBigEndian);
    read_body(path, header, source, body.size(), &mesh);
    source.finish();
  }
  mesh_detail::require_faces(path, mesh);
  return mesh;
}

}  // namespace keel::io
