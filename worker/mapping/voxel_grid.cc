// VoxelGrid of Table III, seed 000. Own hashing (VoxelAccumulator) rather than pcl::VoxelGrid:
// PCL packs the voxel index into a 32-bit integer and refuses clouds whose extent / leaf
// exceeds 2^31 voxels (a 2 km survey at 1 cm leaf does), and it accumulates centroids in
// float. Ours keeps 64-bit indices per axis and double sums; its results equal PCL's where PCL
// works (same origin-anchored grid; checked in tests against pcl::VoxelGrid and bun0).
#include "worker/mapping/filters.h"
#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {

size_t apply_voxel_grid(const VoxelGridFilter& filter, PointCloud& cloud) {
  VoxelAccumulator voxels(filter.leaf_m);
  voxels.add(cloud);
  PointCloud out = voxels.centroids();
  out.t_ns = cloud.t_ns;
  out.frame = cloud.frame;
  const size_t removed = cloud.size() - out.size();
  cloud = std::move(out);
  return removed;
}

}  // namespace keel::mapping
