// Fixed-radius neighbour queries over a 3D point set on a CGAL kd-tree, kept behind a pimpl so
// that callers do not compile CGAL. Serves DBSCAN (Algorithm 1, line 11, seed 001) and
// nearby_vertices() of Algorithm 2 ("we use a KD tree", section 3.3). Queries are const and
// thread-safe once constructed.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace keel::inspect {

class RadiusIndex {
 public:
  // Copies the points; they must be finite (std::invalid_argument otherwise).
  explicit RadiusIndex(const std::vector<Eigen::Vector3d>& points);
  ~RadiusIndex();
  RadiusIndex(RadiusIndex&&) noexcept;
  RadiusIndex& operator=(RadiusIndex&&) noexcept;
  RadiusIndex(const RadiusIndex&) = delete;
  RadiusIndex& operator=(const RadiusIndex&) = delete;

  // Indices, ascending, of the points p in the closed ball (p - query).squaredNorm() <=
  // radius_m^2. The tree only proposes candidates; this exact test decides, so the answer is the
  // one a brute-force scan with the same expression gives.
  void within(const Eigen::Vector3d& query, double radius_m, std::vector<int>* indices) const;
  size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::inspect
