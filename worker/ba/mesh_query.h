// Distance and ray queries against a triangle mesh (the CAD prior), on a CGAL AABB tree kept
// behind a pimpl so that callers do not compile CGAL.
//
// Serves the surface constraint of model-assisted BA (Eq. 4-7, seed 001: h() is the signed
// distance of a feature to the mesh, Eq. 5), the DVL beam raycast factor and the simulator's
// range sensors. Queries are const and thread-safe once the MeshQuery is built.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <vector>

#include "worker/core/triangle_mesh.h"

namespace keel::ba {

// Which part of the closest triangle the closest point lies on.
enum class MeshFeature { kFace, kEdge, kVertex };

struct ClosestPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // closest point on the mesh (mesh frame)
  int face = -1;                                    // index into TriangleMesh::faces
  MeshFeature feature = MeshFeature::kFace;
  double distance_m = 0.0;  // |query - point|
  // Positive on the side the surface normal points to (outside of a closed, outward-oriented
  // mesh), negative inside. Eq. (5), seed 001, with n the pseudonormal below.
  double signed_distance_m = 0.0;
  // Unit normal deciding the sign: the face normal inside a face, the angle-weighted
  // pseudonormal at edges and vertices (Baerentzen & Aanaes 2005), so the sign is right
  // next to edges and corners too.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // any length > 0
  double max_range_m = 1e9;
  double min_range_m = 0.0;  // ignore hits closer than this (e.g. rays leaving the surface)
};

struct RayHit {
  double distance_m = 0.0;  // along the unit direction from origin
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  int face = -1;                                           // index into TriangleMesh::faces
  Eigen::Vector3d face_normal = Eigen::Vector3d::UnitZ();  // unit, from the face's winding
};

class MeshQuery {
 public:
  // Copies what it needs from `mesh`. Faces with zero area (or a repeated index) are left out
  // of the tree: their neighbours' edges cover them. Throws std::invalid_argument when the
  // mesh has no usable face or a face indexes outside the vertex list.
  explicit MeshQuery(const TriangleMesh& mesh);
  ~MeshQuery();
  MeshQuery(MeshQuery&&) noexcept;
  MeshQuery& operator=(MeshQuery&&) noexcept;
  MeshQuery(const MeshQuery&) = delete;
  MeshQuery& operator=(const MeshQuery&) = delete;

  ClosestPoint closest_point(const Eigen::Vector3d& query) const;
  double signed_distance(const Eigen::Vector3d& query) const;
  // First intersection along the ray within [min_range_m, max_range_m]; nullopt if none.
  // Throws std::invalid_argument for a zero or non-finite direction.
  std::optional<RayHit> raycast(const Ray& ray) const;

  // Batch versions; `num_threads` > 1 splits the queries over that many threads.
  std::vector<ClosestPoint> closest_points(const std::vector<Eigen::Vector3d>& queries,
                                           int num_threads = 1) const;
  std::vector<double> signed_distances(const std::vector<Eigen::Vector3d>& queries,
                                       int num_threads = 1) const;
  std::vector<std::optional<RayHit>> raycasts(const std::vector<Ray>& rays,
                                              int num_threads = 1) const;

  size_t num_faces() const;  // faces in the tree (non-degenerate)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::ba
