// OFF mesh reader (ascii OFF, COFF, NOFF, CNOFF, STOFF). See mesh_reader.h.
#include <string>
#include <vector>

#include "worker/io/mesh/mesh_parse_util.h"
#include "worker/io/mesh/mesh_reader.h"

namespace keel::io {
namespace {

using mesh_detail::fail;
using mesh_detail::quoted;

bool is_off_keyword(std::string_view keyword) {
  for (const char* k : {"OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCOFF", "STNOFF", "STCNOFF"}) {
    if (keyword == k) return true;
  }
  return false;
}

int64_t parse_count(const std::filesystem::path& path, size_t line, std::string_view token,
                    const char* what) {
  int64_t count = 0;
  if (!mesh_detail::parse_int64(token, &count) || count < 0) {
    fail(path, line, std::string("expected the number of ") + what + ", got " + quoted(token));
  }
  return count;
}

}  // namespace

TriangleMesh read_off_mesh(const std::filesystem::path& path) {
  const std::string text = mesh_detail::read_file_bytes(path);
  mesh_detail::LineCursor lines(text);
  std::string_view line;
  std::vector<std::string_view> tokens;

  // Header: the keyword, then "nv nf ne" on the same or the next line.
  if (!lines.next_content(&line, '#')) fail(path, 0, "empty file (expected 'OFF')");
  mesh_detail::split_whitespace(line, &tokens);
  if (tokens[0] == "OFF" && tokens.size() > 1 && tokens[1] == "BINARY") {
    fail(path, lines.line_number(), "binary OFF is not supported (expected ascii OFF)");
  }
  if (!is_off_keyword(tokens[0])) {
    fail(path, lines.line_number(), "not an OFF file: expected 'OFF', got " + quoted(tokens[0]));
  }
  tokens.erase(tokens.begin());
  if (tokens.empty()) {
    if (!lines.next_content(&line, '#')) {
      fail(path, lines.line_number(), "truncated: no vertex and face counts after 'OFF'");
    }
    mesh_detail::split_whitespace(line, &tokens);
  }
  if (tokens.size() < 2) fail(path, lines.line_number(), "expected 'vertices faces [edges]'");
  const int64_t num_vertices = parse_count(path, lines.line_number(), tokens[0], "vertices");
  const int64_t num_faces = parse_count(path, lines.line_number(), tokens[1], "faces");
  // Each vertex and face needs a line: more than the file has bytes cannot be right.
  if (num_vertices > static_cast<int64_t>(text.size()) ||
      num_faces > static_cast<int64_t>(text.size())) {
    fail(path, lines.line_number(),
         "counts " + std::to_string(num_vertices) + " vertices, " + std::to_string(num_faces) +
             " faces cannot fit in a file of " + std::to_string(text.size()) + " bytes");
  }

  TriangleMesh mesh;
  mesh.vertices.reserve(num_vertices);
  for (int64_t v = 0; v < num_vertices; ++v) {
    if (!lines.next_content(&line, '#')) {
      fail(path, lines.line_number(),
           "truncated: expected " + std::to_string(num_vertices) +
               " vertices, the file ends after " + std::to_string(v));
    }
    mesh_detail::split_whitespace(line, &tokens);
    if (tokens.size() < 3) fail(path, lines.line_number(), "expected 'x y z'");
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) {
      if (!mesh_detail::parse_double(tokens[i], &p[i])) {
        fail(path, lines.line_number(), "expected a number, got " + quoted(tokens[i]));
      }
    }
    if (!mesh_detail::is_finite(p)) {
      fail(path, lines.line_number(), "vertex has a non-finite coordinate (NaN or inf)");
    }
    mesh.vertices.push_back(p);
  }

  std::vector<int> polygon;
  for (int64_t f = 0; f < num_faces; ++f) {
    if (!lines.next_content(&line, '#')) {
      fail(path, lines.line_number(),
           "truncated: expected " + std::to_string(num_faces) + " faces, the file ends after " +
               std::to_string(f));
    }
    const size_t n = lines.line_number();
    mesh_detail::split_whitespace(line, &tokens);
    int64_t corners = 0;
    if (!mesh_detail::parse_int64(tokens[0], &corners) || corners < 3) {
      fail(path, n, "expected a face 'n i1 ... in' with n >= 3, got " + quoted(tokens[0]));
    }
    // Values after the n indices are an optional face colour.
    if (static_cast<int64_t>(tokens.size()) < corners + 1) {
      fail(path, n,
           "face declares " + std::to_string(corners) + " vertices but lists " +
               std::to_string(tokens.size() - 1));
    }
    polygon.clear();
    for (int64_t i = 1; i <= corners; ++i) {
      int64_t index = 0;
      if (!mesh_detail::parse_int64(tokens[i], &index)) {
        fail(path, n, "expected a vertex index, got " + quoted(tokens[i]));
      }
      if (index < 0 || index >= num_vertices) {
        fail(path, n,
             "vertex index " + std::to_string(index) + " out of range (the file has " +
                 std::to_string(num_vertices) + " vertices)");
      }
      polygon.push_back(static_cast<int>(index));
    }
    mesh_detail::add_polygon_fan(polygon, &mesh.faces);
  }
  mesh_detail::require_faces(path, mesh);
  return mesh;
}

}  // namespace keel::io
