#include "worker/compare/voxel_moments.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "worker/compare/cell_sort.h"
#include "core/parallel_for.h"

namespace keel::compare {

void Moments::add(const Moments& other) {
  if (other.count <= 0.0) return;
  if (count <= 0.0) {
    *this = other;
    return;
  }
  const double total = count + other.count;
  const Eigen::Vector3d delta = other.mean - mean;
  // Chan et al.'s pairwise update: S = S_a + S_b + n_a n_b / n (m_b - m_a)(m_b - m_a)^T.
  scatter += other.scatter + (count * other.count / total) * delta * delta.transpose();
  mean += delta * (other.count / total);
  count = total;
}

LocalPlane fit_plane(const Moments& moments) {
  LocalPlane plane;
  plane.centroid = moments.mean;
  if (moments.count < 3.0) return plane;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(moments.scatter / moments.count);
  plane.eigenvalues = solver.eigenvalues();
  plane.normal = solver.eigenvectors().col(0).normalized();
  plane.valid = plane.eigenvalues[1] > 0.0 && plane.normal.allFinite();
  return plane;
}

VoxelMoments voxelize(const std::vector<Eigen::Vector3f>& points, double voxel_m,
                      bool keep_voxel_of, int threads) {
  const CellSort sorted = sort_into_cells(points, voxel_m, "voxelize", threads);
  VoxelMoments out;
  out.voxel_m = voxel_m;
  const auto& keyed = sorted.keyed;
  std::vector<size_t> begins;  // each voxel's first entry in `keyed`, then keyed.size()
  for (size_t k = 0; k < keyed.size(); ++k)
    if (k == 0 || keyed.key(k) != keyed.key(k - 1)) begins.push_back(k);
  begins.push_back(keyed.size());
  const size_t voxels = begins.size() - 1;
  out.voxels.resize(voxels);
  out.means.resize(voxels);
  if (keep_voxel_of) out.voxel_of.resize(points.size());
  // Voxels are independent, and each sums its points in index order whatever the thread.
  keel::parallel_for(voxels, threads, [&](size_t first, size_t last) {
    for (size_t v = first; v < last; ++v) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (size_t k = begins[v]; k < begins[v + 1]; ++k)
        sum += points[keyed.index(k)].cast<double>();
      Moments& m = out.voxels[v];
      m.count = double(begins[v + 1] - begins[v]);
      m.mean = sum / m.count;
      for (size_t k = begins[v]; k < begins[v + 1]; ++k) {
        const Eigen::Vector3d d = points[keyed.index(k)].cast<double>() - m.mean;
        m.scatter += d * d.transpose();
        if (keep_voxel_of) out.voxel_of[keyed.index(k)] = uint32_t(v);
      }
      out.means[v] = m.mean.cast<float>();
    }
  });
  return out;
}

}  // namespace keel::compare
