// Fixed-radius neighbour queries over a point set on a kd-tree (nanoflann),
// hidden behind a pimpl. Queries are const and may run
// concurrently from several threads.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace keel::mapping {

class RadiusSearch {
 public:
  // Copies the points; a large set is stored in Morton (Z-order) sequence so that the points
  // of a kd-tree leaf, and the leaves near one another, sit together in memory (a small one
  // fits in the cache as it is). Points must be finite.
  explicit RadiusSearch(const std::vector<Eigen::Vector3f>& points);
  ~RadiusSearch();
  RadiusSearch(const RadiusSearch&) = delete;
  RadiusSearch& operator=(const RadiusSearch&) = delete;

  // Number of indexed points p with |p - query| < radius_m (a query point that is itself
  // indexed counts), capped at max_count when max_count > 0 (the search stops early).
  // `radius_m` is the radius in metres (squared internally; never pass r^2 or sqrt r).
  int count_within(const Eigen::Vector3f& query, double radius_m, int max_count = 0) const;
  // count_within(input[spatial_order()[rank]], radius_m, max_count) for max_count > 0, the
  // same answer, found faster: the point's own kd-tree leaf is scanned first, and a count
  // that reaches max_count there needs no tree descent (most outlier-filter queries).
  int count_around(size_t rank, double radius_m, int max_count) const;
  // Indices (unsorted) of all indexed points with |p - query| < radius_m.
  void within(const Eigen::Vector3f& query, double radius_m, std::vector<int>* indices,
              std::vector<float>* squared_distances) const;
  // Input indices in the kd-tree's leaf order ("ranks"): queries issued in this order reuse
  // the cache.
  const std::vector<uint32_t>& spatial_order() const;
  size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::mapping
