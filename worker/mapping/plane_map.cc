#include "worker/mapping/plane_map.h"

#include <Eigen/Eigenvalues>

#include <stdexcept>

#include "core/parallel_for.h"

#include "worker/mapping/kd_points.h"

namespace keel::mapping {
namespace {

using PointSet = KdPoints;
using Tree = KdTree;

LocalPlane fit_plane(const PointSet& set, const std::vector<uint32_t>& indices,
                     const std::vector<float>& squared_distances, size_t found,
                     const PlaneMapOptions& options) {
  LocalPlane plane;
  const double max_d2 = options.max_neighbour_m * options.max_neighbour_m;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t i = 0; i < found; ++i) {
    if (squared_distances[i] > max_d2) continue;
    sum += set.points[indices[i]].cast<double>();
    ++n;
  }
  if (n < options.min_neighbours) return plane;
  const Eigen::Vector3d centroid = sum / n;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < found; ++i) {
    if (squared_distances[i] > max_d2) continue;
    const Eigen::Vector3d d = set.points[indices[i]].cast<double>() - centroid;
    covariance += d * d.transpose();
  }
  covariance /= n;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d l = solver.eigenvalues();  // ascending
  plane.centroid = centroid;
  if (l(0) < options.max_thickness_ratio * l(1) && l(1) > options.min_line_ratio * l(2)) {
    plane.normal = solver.eigenvectors().col(0).normalized();
    plane.planar = true;
  }
  return plane;
}

}  // namespace

struct PlaneMap::Impl {
  PointSet set;
  Tree tree{3, set,
            nanoflann::KDTreeSingleIndexAdaptorParams(
                16, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex)};
  std::vector<LocalPlane> planes;
  size_t planar = 0;
};

PlaneMap::PlaneMap(const std::vector<Eigen::Vector3f>& points, const PlaneMapOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (points.empty()) throw std::invalid_argument("PlaneMap: no points");
  for (const Eigen::Vector3f& p : points)
    if (!p.allFinite()) throw std::invalid_argument("PlaneMap: a point is not finite");
  if (options.neighbours < options.min_neighbours || options.min_neighbours < 3)
    throw std::invalid_argument("PlaneMap: neighbours must be >= min_neighbours >= 3");
  impl_->set.points = points;
  impl_->tree.buildIndex();
  impl_->planes.resize(points.size());
  const size_t k = static_cast<size_t>(options.neighbours);
  parallel_for(points.size(), options.threads, [&](size_t begin, size_t end) {
    std::vector<uint32_t> indices(k);
    std::vector<float> squared(k);
    for (size_t i = begin; i < end; ++i) {
      const size_t found =
          impl_->tree.knnSearch(points[i].data(), k, indices.data(), squared.data());
      impl_->planes[i] = fit_plane(impl_->set, indices, squared, found, options);
    }
  });
  for (const LocalPlane& plane : impl_->planes) impl_->planar += plane.planar ? 1 : 0;
}

PlaneMap::~PlaneMap() = default;

uint32_t PlaneMap::nearest(const Eigen::Vector3d& query, double* squared_distance_m2) const {
  const Eigen::Vector3f q = query.cast<float>();
  uint32_t index = 0;
  float squared = 0.0f;
  impl_->tree.knnSearch(q.data(), 1, &index, &squared);
  *squared_distance_m2 = (impl_->set.points[index].cast<double>() - query).squaredNorm();
  return index;
}

const LocalPlane& PlaneMap::plane(uint32_t index) const { return impl_->planes[index]; }
size_t PlaneMap::size() const { return impl_->set.points.size(); }
size_t PlaneMap::planar_count() const { return impl_->planar; }

}  // namespace keel::mapping
