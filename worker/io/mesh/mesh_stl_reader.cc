// STL mesh reader (ascii and binary). See mesh_reader.h.
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/mesh/mesh_reader.h"

namespace keel::io {
namespace {

using mesh_detail::fail;
using mesh_detail::quoted;

constexpr size_t kBinaryHeaderBytes = 84;    // 80-byte header + uint32 triangle count
constexpr size_t kBinaryTriangleBytes = 50;  // normal, 3 corners (12 floats) + uint16

// STL stores every triangle's corners; this turns identical positions into one vertex.
class VertexMerger {
 public:
  explicit VertexMerger(TriangleMesh* mesh) : mesh_(mesh) {}
  int index_of(const Eigen::Vector3d& p) {
    // +0.0 and -0.0 are the same point; add 0.0 to fold them before hashing the bits.
    const Key key{p.x() + 0.0, p.y() + 0.0, p.z() + 0.0};
    const auto [it, inserted] = index_.try_emplace(key, static_cast<int>(mesh_->vertices.size()));
    if (inserted) mesh_->vertices.push_back(p);
    return it->second;
  }

 private:
  struct Key {
    double x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      uint64_t bits[3];
      std::memcpy(&bits[0], &k.x, 8);
      std::memcpy(&bits[1], &k.y, 8);
      std::memcpy(&bits[2], &k.z, 8);
      uint64_t h = 1469598103934665603ull;
      for (const uint64_t b : bits) h = (h ^ b) * 1099511628211ull + (h >> 29);
      return static_cast<size_t>(h);
    }
  };
  TriangleMesh* mesh_;
  std::unordered_map<Key, int, KeyHash> index_;
};

bool starts_with_solid(std::string_view text) {
  const size_t first = text.find_first_not_of(" \t\r\n");
  return first != std::string_view::npos && text.substr(first, 5) == "solid";
}

bool is_printable_text(std::string_view text) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 127 || (u < 32 && u != '\n' && u != '\r' && u != '\t')) return false;
  }
  return true;
}

uint32_t binary_triangle_count(std::string_view text) {
  uint32_t count = 0;
  std::memcpy(&count, text.data() + 80, 4);  // little endian, as are Keel's hosts
  return count;
}

TriangleMesh read_binary_stl(const std::filesystem::path& path, std::string_view text) {
  const uint32_t count = binary_triangle_count(text);
  TriangleMesh mesh;
  mesh.faces.reserve(count);
  VertexMerger merger(&mesh);
  for (uint32_t t = 0; t < count; ++t) {
    const char* record = text.data() + kBinaryHeaderBytes + size_t{t} * kBinaryTriangleBytes;
    float values[12];
    std::memcpy(values, record, sizeof(values));
    Eigen::Vector3i face;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d p(values[3 + 3 * c], values[4 + 3 * c], values[5 + 3 * c]);
      if (!mesh_detail::is_finite(p)) {
        fail(path, 0,
             "triangle " + std::to_string(t) + " (byte " +
                 std::to_string(kBinaryHeaderBytes + size_t{t} * kBinaryTriangleBytes) +
                 ") has a non-finite corner coordinate (NaN or inf)");
      }
      face[c] = merger.index_of(p);
    }
    mesh.faces.push_back(face);
  }
  return mesh;
}

TriangleMesh read_ascii_stl(const std::filesystem::path& path, std::string_view text) {
  mesh_detail::LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tokens;
  TriangleMesh mesh;
  VertexMerger merger(&mesh);
  bool in_solid = false;
  bool in_facet = false;
  int corners = 0;
  Eigen::Vector3i face;
  size_t facet_line = 0;
  while (lines.next_content(&line, '\0')) {
    const size_t n = lines.line_number();
    mesh_detail::split_whitespace(line, &tokens);
    const std::string_view keyword = tokens[0];
    if (keyword == "solid") {
      if (in_solid) fail(path, n, "'solid' inside a solid (missing 'endsolid')");
      in_solid = true;
    } else if (!in_solid) {
      fail(path, n, "expected 'solid', got " + quoted(keyword));
    } else if (keyword == "facet") {
      if (in_facet) fail(path, n, "'facet' inside a facet (missing 'endfacet')");
      in_facet = true;
      corners = 0;
      facet_line = n;
    } else if (keyword == "vertex") {
      if (!in_facet) fail(path, n, "'vertex' outside a facet");
      if (corners == 3) fail(path, n, "facet has more than 3 vertices");
      if (tokens.size() != 4) fail(path, n, "expected 'vertex x y z'");
      Eigen::Vector3d p;
      for (int i = 0; i < 3; ++i) {
        if (!mesh_detail::parse_double(tokens[1 + i], &p[i])) {
          fail(path, n, "expected a number, got " + quoted(tokens[1 + i]));
        }
      }
      if (!mesh_detail::is_finite(p))
        fail(path, n, "vertex has a non-finite coordinate (NaN or inf)");
      face[corners++] = merger.index_of(p);
    } else if (keyword == "endfacet") {
      if (!in_facet) fail(path, n, "'endfacet' outside a facet");
      if (corners != 3) {
        fail(path, n, "facet has " + std::to_string(corners) + " vertices (expected 3)");
      }
      mesh.faces.push_back(face);
      in_facet = false;
    } else if (keyword == "endsolid") {
      if (in_facet) fail(path, n, "'endsolid' inside a facet");
      in_solid = false;
    } else if (keyword != "outer" && keyword != "endloop") {
      fail(path, n, "unknown STL keyword " + quoted(keyword));
    }
  }
  if (in_facet) {
    fail(path, lines.line_number(),
         "truncated: the facet that starts at line " + std::to_string(facet_line) +
             " has no 'endfacet'");
  }
  if (in_solid) fail(path, lines.line_number(), "truncated: no 'endsolid' at the end of the file");
  return mesh;
}

}  // namespace

TriangleMesh read_stl_mesh(const std::filesystem::path& path) {
  const std::string text = mesh_detail::read_file_bytes(path);
  // Binary when the size fits the header's triangle count, unless the file is plain text that
  // starts with "solid" (then it is ascii whose size happens to fit). Text that is not
  // "solid ..." or bytes that are not text must be binary, so a size mismatch is an error.
  const bool text_solid = starts_with_solid(text) && is_printable_text(text);
  bool binary = false;
  if (!text_solid) {
    if (text.size() < kBinaryHeaderBytes) {
      fail(path, 0,
           "truncated binary STL: " + std::to_string(text.size()) +
               " bytes, shorter than the 84-byte header");
    }
    const uint64_t expected =
        kBinaryHeaderBytes + uint64_t{binary_triangle_count(text)} * kBinaryTriangleBytes;
    if (expected != text.size()) {
      fail(path, 0,
           "truncated or corrupt binary STL: the header declares " +
               std::to_string(binary_triangle_count(text)) + " triangles (" +
               std::to_string(expected) + " bytes) but the file has " +
               std::to_string(text.size()) + " bytes");
    }
    binary = true;
  }
  TriangleMesh mesh = binary ? read_binary_stl(path, text) : read_ascii_stl(path, text);
  mesh_detail::require_faces(path, mesh);
  return mesh;
}

}  // namespace keel::io
