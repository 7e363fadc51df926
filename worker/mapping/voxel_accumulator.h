// Running voxel centroids: points are added in any number of batches and the result equals one
// VoxelGrid pass over their union (sums, not centroids of centroids, are kept). Memory grows
// with the number of occupied voxels, not with the points added, which is what lets
// MapBuilder stream a long mission into a voxelized map at constant memory per structure.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <unordered_map>

#include "worker/core/point_cloud.h"

namespace keel::mapping {

struct VoxelKey {
  int64_t i = 0, j = 0, k = 0;
  bool operator==(const VoxelKey& other) const {
    return i == other.i && j == other.j && k == other.k;
  }
  bool operator<(const VoxelKey& other) const {
    if (i != other.i) return i < other.i;
    if (j != other.j) return j < other.j;
    return k < other.k;
  }
};

struct VoxelKeyHash {
  size_t operator()(const VoxelKey& key) const {
    // Large odd multipliers mix the three axes (Teschner et al. 2003 spatial hashing).
    const uint64_t h = static_cast<uint64_t>(key.i) * 73856093ULL ^
                       static_cast<uint64_t>(key.j) * 19349663ULL ^
                       static_cast<uint64_t>(key.k) * 83492791ULL;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// The voxel of a point: floor(p / leaf) per axis, anchored at the origin like pcl::VoxelGrid.
// Throws std::invalid_argument when p / leaf does not fit a 62-bit index (absurd leaf sizes).
VoxelKey voxel_of(const Eigen::Vector3f& p, double inverse_leaf);

class VoxelAccumulator {
 public:
  // Throws std::invalid_argument unless leaf_m is finite and positive.
  explicit VoxelAccumulator(double leaf_m);

  // Adds every point (non-finite ones throw). Intensity is averaged when every cloud added
  // carries it.
  void add(const PointCloud& cloud);
  // One point per voxel, the centroid, in VoxelKey order; frame "world" is not assumed: the
  // caller sets it.
  PointCloud centroids() const;

  size_t voxel_count() const { return voxels_.size(); }
  uint64_t points_added() const { return points_added_; }
  double leaf_m() const { return leaf_m_; }
  void clear();

 private:
  struct Sum {
    Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
    double intensity = 0.0;
    uint64_t count = 0;
  };
  double leaf_m_;
  double inverse_leaf_;
  bool intensity_everywhere_ = true;
  uint64_t points_added_ = 0;
  std::unordered_map<VoxelKey, Sum, VoxelKeyHash> voxels_;
};

}  // namespace keel::mapping
