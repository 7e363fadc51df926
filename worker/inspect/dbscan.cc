#include "worker/inspect/dbscan.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/inspect/radius_index.h"

namespace keel::inspect {
namespace {

constexpr int kUnvisited = -2;

void check_options(const DbscanOptions& options) {
  if (!(options.eps_m > 0.0) || !std::isfinite(options.eps_m)) {
    throw std::invalid_argument("dbscan: eps_m = " + std::to_string(options.eps_m) +
                                "; expected a finite radius > 0 m");
  }
  if (options.min_pts < 1) {
    throw std::invalid_argument("dbscan: min_pts = " + std::to_string(options.min_pts) +
                                "; expected >= 1");
  }
}

}  // namespace

std::vector<int> dbscan(const std::vector<Eigen::Vector3d>& points, const DbscanOptions& options) {
  check_options(options);
  const RadiusIndex index(points);  // rejects non-finite points
  const int n = static_cast<int>(points.size());
  std::vector<int> labels(n, kUnvisited);
  std::vector<int> neighbours;
  std::vector<int> seeds;
  int next_cluster = 0;
  for (int i = 0; i < n; ++i) {
    if (labels[i] != kUnvisited) continue;
    index.within(points[i], options.eps_m, &neighbours);
    if (static_cast<int>(neighbours.size()) < options.min_pts) {
      labels[i] = kDbscanNoise;  // may still become a border point of a later cluster
      continue;
    }
    const int cluster = next_cluster++;
    labels[i] = cluster;
    seeds = neighbours;
    // Expand the cluster: every density-reachable point joins it.
    for (size_t k = 0; k < seeds.size(); ++k) {
      const int q = seeds[k];
      if (labels[q] == kDbscanNoise) labels[q] = cluster;  // border point
      if (labels[q] != kUnvisited) continue;
      labels[q] = cluster;
      index.within(points[q], options.eps_m, &neighbours);
      if (static_cast<int>(neighbours.size()) >= options.min_pts) {
        seeds.insert(seeds.end(), neighbours.begin(), neighbours.end());  // q is a core point
      }
    }
  }
  return labels;
}

int num_clusters(const std::vector<int>& labels) {
  int max_label = -1;
  for (const int label : labels) max_label = std::max(max_label, label);
  return max_label + 1;
}

}  // namespace keel::inspect
