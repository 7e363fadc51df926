// Per-vertex deviation of the remeshed model (seed 001, section 3.3): how far each vertex of
// M_new stands off M_prior, as the signed distance h of Eq. (5); the heat maps of Figs. 21-22.
#pragma once

#include <vector>

#include "core/triangle_mesh.h"

namespace keel::inspect {

// For every vertex with update_counts[i] > 0, the signed distance of remeshed.vertices[i] to
// `prior` (positive outside); 0 for the others. Same vertex count and order in both meshes.
// Only the part of the prior that can hold the closest points is put in the distance tree:
// faces with a vertex within 2 |v_new - v_prior| + (longest edge) of a moved vertex. The
// closest point c to v_new satisfies |c - v_new| <= |v_prior - v_new|, so |c - v_prior| <=
// 2 |v_new - v_prior|, and every vertex of c's face, hence every face around it (which the
// sign's pseudonormals use), is within one edge of c.
std::vector<double> vertex_deviations(const TriangleMesh& prior, const TriangleMesh& remeshed,
                                      const std::vector<int>& update_counts);

}  // namespace keel::inspect
