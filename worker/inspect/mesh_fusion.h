// Algorithm 2 of seed 001 (section 3.3): fuse the shapes detected at each camera pose into a
// copy of the prior mesh, moving each CAD vertex along the camera ray to the shape it meets and
// averaging over views with the recursive moving average of Eq. (15).
#pragma once

#include <vector>

#include "core/pose.h"
#include "core/triangle_mesh.h"
#include "worker/inspect/inspect_options.h"
#include "worker/inspect/radius_index.h"
#include "worker/inspect/shape_detection.h"

namespace keel::inspect {

class MeshFusion {
 public:
  // Line 1: M_new = M_prior (a deep copy); the kd-tree over its vertices serves
  // nearby_vertices(). Vertices must be finite.
  MeshFusion(const TriangleMesh& prior, const InspectOptions& options);

  // Lines 5-14 for one pose: the vertices within view_range_m of the camera centre, each ray
  // camera centre -> vertex against each shape detected at that pose (in that camera's frame).
  // A ray meeting two shapes of the same view updates its vertex twice, as the loops of lines
  // 6-13 do. Returns the number of moving-average updates (evaluations of line 11).
  int fuse_view(const Pose3& T_world_camera, const std::vector<DetectedShape>& shapes);

  // M_new: the prior's faces and colours, the vertices as fused so far. The prior's vertex
  // normals are dropped once a vertex has moved: they would no longer match the surface.
  const TriangleMesh& mesh() const { return mesh_; }
  // n of Eq. (15) per vertex: how many intersections were averaged into it (0: untouched).
  const std::vector<int>& update_counts() const { return counts_; }

 private:
  void moving_average(int vertex, const Eigen::Vector3d& p_world);

  TriangleMesh mesh_;
  std::vector<int> counts_;
  std::vector<Eigen::Vector3d> prior_vertices_;  // V of M_prior, where rays are aimed
  RadiusIndex prior_index_;
  InspectOptions options_;
  std::vector<int> nearby_;  // scratch
};

}  // namespace keel::inspect
