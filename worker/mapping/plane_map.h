// A reference map as local planes, for point-to-plane registration (Chen and Medioni 1992;
// the planar-patch test of LOAM / FAST-LIO): each map point carries the plane fitted to its k
// nearest neighbours, kept only where the neighbourhood is planar, so a query point is matched
// to the plane of its nearest map point. nanoflann behind a pimpl.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace keel::mapping {

struct PlaneMapOptions {
  int neighbours = 10;           // k of the plane fit
  double max_neighbour_m = 1.0;  // neighbours farther than this are not part of the plane
  int min_neighbours = 5;        // fewer (within max_neighbour_m): no plane
  // Planar neighbourhood: with l0 <= l1 <= l2 the covariance's eigenvalues, the thickness
  // across the plane is small against its extent (l0 < ratio * l1) and the neighbourhood is not
  // a line (l1 > line_ratio * l2), where the normal would be free to turn about it.
  double max_thickness_ratio = 0.1;
  double min_line_ratio = 0.02;
  int threads = 2;
};

struct LocalPlane {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit; zero when not planar
  bool planar = false;
};

class PlaneMap {
 public:
  // Copies the points and fits every point's plane. Throws std::invalid_argument for an empty
  // set or a non-finite point.
  PlaneMap(const std::vector<Eigen::Vector3f>& points, const PlaneMapOptions& options = {});
  ~PlaneMap();
  PlaneMap(const PlaneMap&) = delete;
  PlaneMap& operator=(const PlaneMap&) = delete;

  // The nearest map point to `query` and its squared distance; const, may run concurrently.
  uint32_t nearest(const Eigen::Vector3d& query, double* squared_distance_m2) const;
  const LocalPlane& plane(uint32_t index) const;
  size_t size() const;
  size_t planar_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::mapping
