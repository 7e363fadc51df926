// Nearest-neighbour queries over a fixed point set on a kd-tree (nanoflann, behind a pimpl so
// its header stays in one translation unit). Queries are const and may run concurrently.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace keel::compare {

struct Neighbour {
  uint32_t index = 0;       // into the constructor's points
  double distance_m = 0.0;  // Euclidean, computed in double from the float coordinates
};

class NearestIndex {
 public:
  // Copies the points. Throws std::invalid_argument for an empty set or a non-finite point.
  explicit NearestIndex(const std::vector<Eigen::Vector3f>& points);
  ~NearestIndex();
  NearestIndex(const NearestIndex&) = delete;
  NearestIndex& operator=(const NearestIndex&) = delete;

  // The indexed point closest to `query` (the lowest index among exact ties is not promised).
  Neighbour nearest(const Eigen::Vector3f& query) const;
  // Indices of the indexed points with |p - query| <= radius_m, unsorted.
  void within(const Eigen::Vector3f& query, double radius_m, std::vector<uint32_t>* indices) const;
  size_t size() const;
  const Eigen::Vector3f& point(uint32_t index) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::compare
