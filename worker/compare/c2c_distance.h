// Cloud-to-cloud (C2C) distance as CloudCompare defines it: for every point of the compared
// cloud, the Euclidean distance to the nearest point of the reference cloud (no local model).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "worker/compare/nearest_index.h"
#include "worker/compare/point_grid.h"

namespace keel::compare {

// Distances in metres, one per compared point, computed on `threads` threads. Throws
// std::invalid_argument for a non-finite compared point.
std::vector<float> c2c_distances(const NearestIndex& reference,
                                 const std::vector<Eigen::Vector3f>& compared, int threads = 2);
// The same distances from grids (faster on dense maps), one per point of `compared` in the
// order its constructor was given them; the points are visited cell by cell, so consecutive
// queries read the same cells of the reference.
std::vector<float> c2c_distances(const PointGrid& reference, const PointGrid& compared,
                                 int threads = 2);

}  // namespace keel::compare
