// Points bucketed into cubic voxels, each summarised by its count, mean and scatter matrix
// (sum of (p - mean)(p - mean)^T). The moments of a union of voxels merge exactly (parallel
// axis theorem), so a local plane over a neighbourhood of voxels costs a few merges instead of
// a pass over every point: M3C2's normals and the ICP's reference planes use that.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace keel::compare {

struct Moments {
  double count = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();

  void add(const Moments& other);  // exact merge
};

struct LocalPlane {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // eigenvector of the smallest eigenvalue
  // Eigenvalues of the covariance, ascending: l0 <= l1 <= l2 (l0 small on a plane).
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  bool valid = false;  // >= 3 points and l1 > 0
};
LocalPlane fit_plane(const Moments& moments);

struct VoxelMoments {
  double voxel_m = 0.0;
  std::vector<Moments> voxels;         // one per occupied voxel, in (i, j, k) order
  std::vector<uint32_t> voxel_of;      // per input point: its voxel; empty unless asked
  std::vector<Eigen::Vector3f> means;  // voxels[v].mean as float, for a kd-tree
};

// Throws std::invalid_argument for a non-positive voxel size or a non-finite point. The result
// does not depend on `threads`.
VoxelMoments voxelize(const std::vector<Eigen::Vector3f>& points, double voxel_m,
                      bool keep_voxel_of = false, int threads = 1);

}  // namespace keel::compare
