#include "worker/io/mesh/mesh_ply_writer.h"

#include <stdexcept>
#include <string>

#include "worker/io/mesh/mesh_ply_binary_writer.h"

namespace keel::io {
namespace {

void check_mesh_for_writing(const TriangleMesh& mesh) {
  const size_t n = mesh.vertices.size();
  if (mesh.has_vertex_normals() && mesh.vertex_normals.size() != n) {
    throw std::invalid_argument("write_ply_mesh: vertex_normals has " +
                                std::to_string(mesh.vertex_normals.size()) + " entries, expected " +
                                std::to_string(n));
  }
  if (mesh.has_vertex_colors() && mesh.vertex_colors.size() != n) {
    throw std::invalid_argument("write_ply_mesh: vertex_colors has " +
                                std::to_string(mesh.vertex_colors.size()) + " entries, expected " +
                                std::to_string(n));
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if ((mesh.faces[f].array() < 0).any() || (mesh.faces[f].array() >= static_cast<int>(n)).any()) {
      throw std::invalid_argument("write_ply_mesh: face " + std::to_string(f) +
                                  " has a vertex index outside [0, " + std::to_string(n) + ")");
    }
  }
}

}  // namespace

void write_ply_mesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                    const std::vector<ScalarField>& vertex_fields,
                    const PlyMeshWriteOptions& options) {
  check_mesh_for_writing(mesh);
  check_scalar_fields(vertex_fields, mesh.vertices.size(),
                      {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"});
  const std::string position_type = options.double_positions ? "double" : "float";
  std::string header = "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  for (const char* axis : {"x", "y", "z"})
    header += "property " + position_type + " " + axis + "\n";
  if (mesh.has_vertex_normals())
    header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (mesh.has_vertex_colors()) {
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  }
  for (const auto& field : vertex_fields) header += "property float " + field.name + "\n";
  header += "element face " + std::to_string(mesh.faces.size()) + "\n";
  header += "property list uchar int vertex_indices\n";

  const size_t vertex_bytes = (options.double_positions ? 24 : 12) +
                              (mesh.has_vertex_normals() ? 12 : 0) +
                              (mesh.has_vertex_colors() ? 3 : 0) + 4 * vertex_fields.size();
  mesh_detail::PlyBinaryWriter writer(path);
  writer.begin(header, vertex_bytes * mesh.vertices.size() + 13 * mesh.faces.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      if (options.double_positions) {
        writer.put(mesh.vertices[i][c]);
      } else {
        writer.put(static_cast<float>(mesh.vertices[i][c]));
      }
    }
    if (mesh.has_vertex_normals()) {
      for (int c = 0; c < 3; ++c) writer.put(static_cast<float>(mesh.vertex_normals[i][c]));
    }
    if (mesh.has_vertex_colors()) {
      for (int c = 0; c < 3; ++c) writer.put(mesh.vertex_colors[i][c]);
    }
    for (const auto& field : vertex_fields) writer.put(field.values[i]);
  }
  for (const auto& face : mesh.faces) {
    writer.put(uint8_t{3});
    for (int c = 0; c < 3; ++c) writer.put(static_cast<int32_t>(face[c]));
  }
  writer.finish();
}

}  // namespace keel::io
