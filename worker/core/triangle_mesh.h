// An indexed triangle mesh (CAD models, remeshed hulls).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace keel {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;  // counter-clockwise seen from outside

  size_t num_vertices() const { return vertices.size(); }
  size_t num_faces() const { return faces.size(); }
};

}  // namespace keel
