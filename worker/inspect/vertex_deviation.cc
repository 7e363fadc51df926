#include "worker/inspect/vertex_deviation.h"

#include <algorithm>
#include <cmath>

#include "core/mesh_query.h"
#include "worker/inspect/radius_index.h"

namespace keel::inspect {
namespace {

double longest_edge(const TriangleMesh& mesh) {
  double longest_sq = 0.0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      longest_sq =
          std::max(longest_sq, (mesh.vertices[f[k]] - mesh.vertices[f[(k + 1) % 3]]).squaredNorm());
    }
  }
  return std::sqrt(longest_sq);
}

// The faces of `prior` that can hold the closest point to a moved vertex (see the header).
TriangleMesh local_prior(const TriangleMesh& prior, const TriangleMesh& remeshed,
                         const std::vector<int>& moved) {
  const RadiusIndex index(prior.vertices);
  const double edge = longest_edge(prior);
  std::vector<char> near(prior.vertices.size(), 0);
  std::vector<int> found;
  for (const int i : moved) {
    const double move = (remeshed.vertices[i] - prior.vertices[i]).norm();
    index.within(prior.vertices[i], 2.0 * move + edge, &found);
    for (const int j : found) near[j] = 1;
  }
  TriangleMesh local;
  local.vertices = prior.vertices;  // same indices; unused vertices are never queried
  for (const Eigen::Vector3i& f : prior.faces) {
    if (near[f[0]] || near[f[1]] || near[f[2]]) local.faces.push_back(f);
  }
  return local;
}

}  // namespace

std::vector<double> vertex_deviations(const TriangleMesh& prior, const TriangleMesh& remeshed,
                                      const std::vector<int>& update_counts) {
  std::vector<double> deviation(remeshed.vertices.size(), 0.0);
  std::vector<int> moved;
  std::vector<Eigen::Vector3d> queries;
  for (size_t i = 0; i < update_counts.size(); ++i) {
    if (update_counts[i] == 0) continue;
    moved.push_back(static_cast<int>(i));
    queries.push_back(remeshed.vertices[i]);
  }
  if (moved.empty()) return deviation;
  const keel::MeshQuery query(local_prior(prior, remeshed, moved));
  const std::vector<double> h = query.signed_distances(queries);  // Eq. (5)
  for (size_t k = 0; k < moved.size(); ++k) deviation[moved[k]] = h[k];
  return deviation;
}

}  // namespace keel::inspect
