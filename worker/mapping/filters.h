// The filters of Table III, seed 000 (CropBox, VoxelGrid, ROR, DROR), as plain functions on a
// keel::PointCloud. Each keeps every per-point field in step with the positions.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"

namespace keel::mapping {

// Removes points inside or outside an axis-aligned box (bounds inclusive: a point on the
// boundary is inside, as pcl::CropBox has it).
struct CropBoxFilter {
  Eigen::Vector3d min_m{-1.0, -1.0, -1.0};
  Eigen::Vector3d max_m{1.0, 1.0, 1.0};
  bool remove_inside = false;  // false: "remove points outside" (keep the box's content)
};

// Replaces the points of each occupied voxel by their centroid (the average intensity with it;
// ring and per-point time are dropped, a centroid has neither). The grid is anchored at the
// origin, voxel (i,j,k) = floor(p / leaf), as pcl::VoxelGrid's is; output is in
// first-occupied order. Voxel indices are 64-bit per axis: any extent/leaf works, including
// those that overflow pcl::VoxelGrid's 32-bit linear index ("Leaf size is too small").
struct VoxelGridFilter {
  double leaf_m = 0.05;
};

// Radius outlier removal [49] with pcl::RadiusOutlierRemoval's semantics, checked against PCL's
// published bun0 answer: keep a point iff at least `min_neighbors` OTHER points lie within
// radius_m (equivalently: the count including the point is > min_neighbors).
struct RadiusOutlierFilter {
  double radius_m = 0.1;
  int min_neighbors = 5;
};

// Dynamic radius outlier removal, Charron et al. 2018 (seed 000 ref. [48]): the search radius
// grows with range because a spinning lidar's point spacing does,
//   SR = max(beta * alpha * r_xy, SR_min),
// with alpha the sensor's horizontal angular resolution given in DEGREES (Table IV: 0.2 for a
// VLP-16 at 10 Hz, 0.5 for the sonar) and converted to radians, and r_xy = sqrt(x^2 + y^2) the
// horizontal range from the scan origin, so DROR only makes sense on a scan in its sensor
// frame. A point is kept iff the count within SR, the point itself included, is >= k_min
// (as the reference implementation counts a kd-tree radius search). Defaults: Table IV lidar.
struct DrorFilter {
  double beta = 3.0;
  double alpha_deg = 0.2;
  int k_min = 4;
  double sr_min_m = 0.01;
};

// Each returns the number of points removed. `threads` parallelises the neighbour counts.
size_t apply_crop_box(const CropBoxFilter& filter, PointCloud& cloud);
size_t apply_voxel_grid(const VoxelGridFilter& filter, PointCloud& cloud);
size_t apply_radius_outlier(const RadiusOutlierFilter& filter, PointCloud& cloud, int threads = 2);
size_t apply_dror(const DrorFilter& filter, PointCloud& cloud, int threads = 2);

// DROR's search radius for a point at horizontal range r_xy_m.
double dror_search_radius(const DrorFilter& filter, double r_xy_m);

// The same decisions as masks over `points` (1: kept), for callers that carry other per-point
// data along (the tiled filters' ownership flags).
std::vector<uint8_t> crop_box_keep(const CropBoxFilter& filter,
                                   const std::vector<Eigen::Vector3f>& points);
std::vector<uint8_t> radius_outlier_keep(const RadiusOutlierFilter& filter,
                                         const std::vector<Eigen::Vector3f>& points,
                                         int threads = 2);
std::vector<uint8_t> dror_keep(const DrorFilter& filter, const std::vector<Eigen::Vector3f>& points,
                               int threads = 2);

}  // namespace keel::mapping
