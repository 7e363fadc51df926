// nanoflann (header-only, Debian libnanoflann-dev), as worker/mapping/radius_search.cc uses it.
#include "worker/compare/nearest_index.h"

#include <nanoflann.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace keel::compare {
namespace {

struct PointSet {
  const std::vector<Eigen::Vector3f>* points = nullptr;
  size_t kdtree_get_point_count() const { return points->size(); }
  float kdtree_get_pt(size_t index, size_t axis) const { return (*points)[index][axis]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointSet>,
                                                 PointSet, 3, uint32_t>;

// Collects indices within a squared radius (nanoflann's RadiusResultSet keeps pairs; indices
// alone are all the callers need).
class IndexResultSet {
 public:
  IndexResultSet(float squared_radius, std::vector<uint32_t>* out)
      : squared_radius_(squared_radius), out_(out) {}
  bool addPoint(float squared_distance, uint32_t index) {
    if (squared_distance <= squared_radius_) out_->push_back(index);
    return true;
  }
  float worstDist() const { return squared_radius_; }
  bool full() const { return true; }

 private:
  float squared_radius_;
  std::vector<uint32_t>* out_;
};

}  // namespace

struct NearestIndex::Impl {
  std::vector<Eigen::Vector3f> points;
  PointSet set;
  std::unique_ptr<Tree> tree;
};

NearestIndex::NearestIndex(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()) {
  if (points.empty()) throw std::invalid_argument("nearest-neighbour index: no points");
  for (size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw std::invalid_argument("nearest-neighbour index: point " + std::to_string(i) +
                                  " is not finite");
  impl_->points = points;
  impl_->set.points = &impl_->points;
  impl_->tree =
      std::make_unique<Tree>(3, impl_->set, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  impl_->tree->buildIndex();
}

NearestIndex::~NearestIndex() = default;

Neighbour NearestIndex::nearest(const Eigen::Vector3f& query) const {
  uint32_t index = 0;
  float squared = 0.0f;
  nanoflann::KNNResultSet<float, uint32_t> result(1);
  result.init(&index, &squared);
  impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams(10, 0.0f, false));
  const Eigen::Vector3d d = (impl_->points[index].cast<double>() - query.cast<double>());
  return {index, d.norm()};
}

void NearestIndex::within(const Eigen::Vector3f& query, double radius_m,
                          std::vector<uint32_t>* indices) const {
  indices->clear();
  IndexResultSet result(static_cast<float>(radius_m * radius_m), indices);
  impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams(10, 0.0f, false));
}

size_t NearestIndex::size() const { return impl_->points.size(); }

const Eigen::Vector3f& NearestIndex::point(uint32_t index) const { return impl_->points[index]; }

}  // namespace keel::compare
