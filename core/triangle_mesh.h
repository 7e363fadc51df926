// An indexed triangle mesh (CAD models, remeshed hulls).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace keel {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;  // counter-clockwise seen from outside
  // Optional per-vertex data, as a PLY file may carry it: empty or vertices.size().
  std::vector<Eigen::Vector3d> vertex_normals;              // unit, outward
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> vertex_colors;  // RGB

  size_t num_vertices() const { return vertices.size(); }
  size_t num_faces() const { return faces.size(); }
  bool has_vertex_normals() const { return !vertex_normals.empty(); }
  bool has_vertex_colors() const { return !vertex_colors.empty(); }
};

}  // namespace keel
