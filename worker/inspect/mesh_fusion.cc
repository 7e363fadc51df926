#include "worker/inspect/mesh_fusion.h"

#include <optional>

#include "worker/inspect/shape_raycaster.h"

namespace keel::inspect {

MeshFusion::MeshFusion(const TriangleMesh& prior, const InspectOptions& options)
    : mesh_(prior),  // line 1
      counts_(prior.vertices.size(), 0),
      prior_vertices_(prior.vertices),
      prior_index_(prior.vertices),
      options_(options) {}

// Eq. (15): v_{n+1} = (p + n v_n) / (n + 1), with v_0 the prior's vertex and n incremented
// after every update, so after N updates the vertex is the mean of its N intersections.
void MeshFusion::moving_average(int vertex, const Eigen::Vector3d& p_world) {
  const double n = counts_[vertex];
  mesh_.vertices[vertex] = (p_world + n * mesh_.vertices[vertex]) / (n + 1.0);
  ++counts_[vertex];
}

int MeshFusion::fuse_view(const Pose3& T_world_camera, const std::vector<DetectedShape>& shapes) {
  if (shapes.empty()) return 0;  // nothing can meet a ray: skip the vertex search
  // Line 5: nearby_vertices(pose, M_prior). Distances from the prior's vertices, which the
  // tree holds, not from the vertices moved so far.
  prior_index_.within(T_world_camera.translation(), options_.view_range_m, &nearby_);
  const Pose3 T_camera_world = T_world_camera.inverse();
  int updates = 0;
  for (const DetectedShape& detected : shapes) {  // line 6
    const ShapeRaycaster raycaster(detected.shape);
    for (const int i : nearby_) {  // line 7
      // The ray goes towards the prior's vertex (V_n[i] of M_prior, as in Fig. 12).
      const Eigen::Vector3d vertex_camera = T_camera_world * prior_vertices_[i];
      const std::optional<Eigen::Vector3d> p_camera =
          raycaster.intersect(vertex_camera, options_.max_behind_vertex_m);  // lines 8-10
      if (!p_camera) continue;
      moving_average(i, T_world_camera * *p_camera);  // line 11
      ++updates;
    }
  }
  if (updates > 0) mesh_.vertex_normals.clear();
  return updates;
}

}  // namespace keel::inspect
