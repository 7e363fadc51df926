// DBSCAN (Ester et al. 1996), the clustering of Algorithm 1, line 11, seed 001, with
// neighbourhoods from a kd-tree (RadiusIndex).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace keel::inspect {

struct DbscanOptions {
  double eps_m = 0.12;  // neighbourhood radius; closed ball |p - q| <= eps_m
  int min_pts = 3;      // a core point has >= min_pts neighbours, itself included
};

constexpr int kDbscanNoise = -1;

// One label per point: clusters 0..k-1, numbered in the order their first core point appears
// in `points`; kDbscanNoise for noise. A border point reachable from several clusters joins
// the first of them (the classic, index-order rule), so labels depend only on the point order.
// Throws std::invalid_argument for non-finite points, eps_m <= 0 or min_pts < 1.
std::vector<int> dbscan(const std::vector<Eigen::Vector3d>& points, const DbscanOptions& options);

// Number of clusters in a label vector from dbscan().
int num_clusters(const std::vector<int>& labels);

}  // namespace keel::inspect
