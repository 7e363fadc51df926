// Wavefront OBJ mesh reader. See mesh_reader.h.
#include <string>
#include <vector>

#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/mesh/mesh_reader.h"

namespace keel::io {
namespace {

using mesh_detail::fail;
using mesh_detail::quoted;

// Resolves a 1-based OBJ index (negative = relative to the end of the list so far) against
// the `count` elements defined before this line; -1 if it is out of range.
int64_t resolve_index(int64_t index, size_t count) {
  const int64_t n = static_cast<int64_t>(count);
  if (index > 0 && index <= n) return index - 1;
  if (index < 0 && -index <= n) return n + index;
  return -1;
}

struct ObjCounts {
  size_t positions = 0;
  size_t texcoords = 0;
  size_t normals = 0;
};

// One corner "v", "v/vt", "v/vt/vn" or "v//vn"; returns the 0-based position index.
int parse_corner(const std::filesystem::path& path, size_t line, std::string_view corner,
                 const ObjCounts& counts) {
  const char* names[3] = {"vertex", "texture coordinate", "normal"};
  const char* plural[3] = {"vertices", "texture coordinates", "normals"};
  const size_t defined[3] = {counts.positions, counts.texcoords, counts.normals};
  int64_t position = -1;
  size_t part = 0;
  size_t start = 0;
  while (true) {
    const size_t slash = corner.find('/', start);
    const std::string_view field = corner.substr(
        start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    if (part > 2) fail(path, line, "face corner " + quoted(corner) + " has more than 3 fields");
    const bool optional = part == 1;  // "v//vn" leaves the texture index out
    if (!(field.empty() && optional)) {
      int64_t index = 0;
      if (!mesh_detail::parse_int64(field, &index) || index == 0) {
        fail(path, line,
             "face corner " + quoted(corner) + ": expected a non-zero " + names[part] +
                 " index, got " + quoted(field));
      }
      const int64_t resolved = resolve_index(index, defined[part]);
      if (resolved < 0) {
        fail(path, line,
             std::string(names[part]) + " index " + std::to_string(index) + " out of range (" +
                 std::to_string(defined[part]) + " " + plural[part] + " defined before this line)");
      }
      if (part == 0) position = resolved;
    }
    if (slash == std::string_view::npos) break;
    start = slash + 1;
    ++part;
  }
  return static_cast<int>(position);
}

}  // namespace

TriangleMesh read_obj_mesh(const std::filesystem::path& path) {
  const std::string text = mesh_detail::read_file_bytes(path);
  mesh_detail::LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<int> polygon;
  ObjCounts counts;
  TriangleMesh mesh;
  while (lines.next_content(&line, '#')) {
    const size_t n = lines.line_number();
    mesh_detail::split_whitespace(line, &tokens);
    const std::string_view keyword = tokens[0];
    if (keyword == "v") {
      // "v x y z [w]" or "v x y z r g b" (a common colour extension): x y z are first.
      if (tokens.size() < 4) fail(path, n, "expected 'v x y z'");
      Eigen::Vector3d p;
      for (int i = 0; i < 3; ++i) {
        if (!mesh_detail::parse_double(tokens[1 + i], &p[i])) {
          fail(path, n, "expected a number, got " + quoted(tokens[1 + i]));
        }
      }
      if (!mesh_detail::is_finite(p))
        fail(path, n, "vertex has a non-finite coordinate (NaN or inf)");
      mesh.vertices.push_back(p);
      ++counts.positions;
    } else if (keyword == "vt") {
      ++counts.texcoords;
    } else if (keyword == "vn") {
      ++counts.normals;
    } else if (keyword == "f") {
      if (tokens.size() < 4) {
        fail(path, n,
             "face has " + std::to_string(tokens.size() - 1) + " corners (expected at least 3)");
      }
      polygon.clear();
      for (size_t i = 1; i < tokens.size(); ++i) {
        polygon.push_back(parse_corner(path, n, tokens[i], counts));
      }
      mesh_detail::add_polygon_fan(polygon, &mesh.faces);
    }
    // Everything else (o, g, s, usemtl, mtllib, l, p, vp, ...) carries no surface geometry.
  }
  mesh_detail::require_faces(path, mesh);
  return mesh;
}

}  // namespace keel::io
