#include "worker/compare/voxel_moments.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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
                      bool keep_voxel_of) {
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m))
    throw std::invalid_argument("voxel size must be a positive number of metres");
  VoxelMoments out;
  out.voxel_m = voxel_m;
  // Keys: 21 bits per axis around the first point's voxel; a cloud wider than 2^21 voxels is
  // refused (at 1 cm that is 20 km).
  std::vector<std::pair<uint64_t, uint32_t>> keyed(points.size());
  if (points.empty()) return out;
  const double inv = 1.0 / voxel_m;
  Eigen::Vector3d lo = points.front().cast<double>();
  for (const auto& p : points) {
    if (!p.allFinite()) throw std::invalid_argument("voxelize: a point is not finite");
    lo = lo.cwiseMin(p.cast<double>());
  }
  constexpr int64_t kMax = (int64_t(1) << 21) - 1;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d c = (points[i].cast<double>() - lo) * inv;
    const int64_t x = int64_t(std::floor(c.x())), y = int64_t(std::floor(c.y())),
                  z = int64_t(std::floor(c.z()));
    if (x > kMax || y > kMax || z > kMax)
      throw std::invalid_argument("voxelize: the cloud spans more than 2^21 voxels of " +
                                  std::to_string(voxel_m) + " m");
    keyed[i] = {uint64_t(x) << 42 | uint64_t(y) << 21 | uint64_t(z), uint32_t(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  if (keep_voxel_of) out.voxel_of.resize(points.size());
  for (size_t begin = 0; begin < keyed.size();) {
    size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    while (end < keyed.size() && keyed[end].first == keyed[begin].first) {
      sum += points[keyed[end].second].cast<double>();
      ++end;
    }
    Moments m;
    m.count = double(end - begin);
    m.mean = sum / m.count;
    for (size_t k = begin; k < end; ++k) {
      const Eigen::Vector3d d = points[keyed[k].second].cast<double>() - m.mean;
      m.scatter += d * d.transpose();
      if (keep_voxel_of) out.voxel_of[keyed[k].second] = uint32_t(out.voxels.size());
    }
    out.voxels.push_back(m);
    out.means.push_back(m.mean.cast<float>());
    begin = end;
  }
  return out;
}

}  // namespace keel::compare
