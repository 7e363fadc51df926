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

#include "core/triangle_mesh.h"

namespace keel {

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
  // Unit normal of the smooth surface the facets sample (Phong): the hit face's corner normals
  // blended with the hit point's barycentric coordinates. A corner's normal is the
  // angle-weighted mean of the faces around its vertex that are reached from the hit face
  // across edges of at most 30 degrees (smoothing groups; a steeper edge is a crease). So it is
  // continuous across every edge of at most 30 degrees, and equals face_normal on flat faces
  // up to sharp edges.
  Eigen::Vector3d interpolated_normal = Eigen::Vector3d::UnitZ();
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

  // Faces (indices into TriangleMesh::faces, degenerate ones left out) at a distance of at
  // most `radius_m` from `center`, exactly: an AABB-tree box query filtered by the
  // point-triangle distance. Each face's distance goes to `distances_m` when it is not null.
  std::vector<int> faces_within(const Eigen::Vector3d& center, double radius_m,
                                std::vector<double>* distances_m = nullptr) const;
  // closest_point() restricted to `faces` (as returned by faces_within), by brute force over
  // them. Same feature, pseudonormal and sign rules. `faces` must not be empty.
  ClosestPoint closest_point_among(const Eigen::Vector3d& query,
                                   const std::vector<int>& faces) const;

 private:
  friend class LocalClosestPoint;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Exact closest-point queries for ONE point that moves little between calls: a landmark
// across Ceres iterations, where the closest triangle rarely changes.
//
// Why (issue 6, measured in tests/bench/mesh_query_bench.cc): an AABB-tree closest-point query
// costs microseconds, brute force over the few faces around the last answer a fraction of it.
//
// Soundness: at an anchor q0 with distance d0 to the mesh, keep every face within d0 + 2 rho
// of q0 (the candidates). For any q with |q - q0| <= rho the closest face g of q has
//   d(q0, g) <= d(q, g) + rho <= d(q, f0) + rho <= d0 + 2 rho
// (f0 the closest face of q0), so g is a candidate, and brute force over the candidates gives
// the exact closest point, equal to MeshQuery::closest_point up to ties. The candidates are
// sorted by d(q0, g), and d(q, g) >= d(q0, g) - |q - q0|, so the brute force stops at the first
// candidate that cannot beat the best so far: usually after the faces around the closest
// feature. We chose this ball over a 1-ring around the cached face: a 1-ring misses faces where
// the mesh folds back (a thin keel, the far side of a box) and needs a validity test per call,
// the ball needs none. rho shrinks so that at most max_candidates faces are kept; below
// min_move_bound_m (far from a fine mesh) the tree answers.
//
// Re-anchoring: a call between rho and 2 rho from the anchor (the point drifts) re-anchors
// there with one ball query on the tree (the old candidates bound d0). A call farther away (a
// jump) is answered by the tree and moves the anchor only when the next far call lands within
// rho of it: in a BA a jump is mostly a Levenberg-Marquardt trial step (a large x_gM step moves
// every landmark in the model frame) that is rejected, after which the point is back near the
// anchor. Re-anchoring at every jump re-anchored a third of all calls in bench_ba.
//
// Not thread-safe: one per point, used by one thread at a time. `mesh` must outlive it.
struct LocalClosestPointOptions {
  // rho. Landmarks move by millimetres per BA iteration after the SLAM initialisation; 5 cm
  // keeps a few dozen faces of a 10 cm-grid hull and re-anchors a few times per solve.
  double move_bound_m = 0.05;
  int max_candidates = 48;
  double min_move_bound_m = 1e-3;
};

class LocalClosestPoint {
 public:
  explicit LocalClosestPoint(const MeshQuery& mesh, const LocalClosestPointOptions& options = {});

  // Equals mesh.closest_point(query) (distance, point and signed distance; the face may be
  // another one at the same distance). Throws std::invalid_argument for a non-finite query.
  ClosestPoint closest_point(const Eigen::Vector3d& query);

  int tree_queries() const { return tree_queries_; }      // re-anchoring and uncached calls
  int cached_queries() const { return cached_queries_; }  // answered from the candidates
  double move_bound_m() const { return move_bound_m_; }   // rho at the current anchor
  size_t num_candidates() const { return candidates_.size(); }

 private:
  ClosestPoint re_anchor(const Eigen::Vector3d& query, double moved_m);

  const MeshQuery* mesh_;
  LocalClosestPointOptions options_;
  bool anchored_ = false;
  Eigen::Vector3d anchor_ = Eigen::Vector3d::Zero();
  double move_bound_m_ = 0.0;  // 0: the candidates are not valid, use the tree
  bool has_pending_ = false;   // the last far call, answered by the tree
  Eigen::Vector3d pending_ = Eigen::Vector3d::Zero();
  std::vector<int> candidates_;                // sorted by their distance to the anchor
  std::vector<double> candidate_distances_m_;  // parallel: that distance
  int tree_queries_ = 0;
  int cached_queries_ = 0;
};

}  // namespace keel
