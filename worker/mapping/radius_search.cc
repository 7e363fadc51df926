// nanoflann (header-only, Debian libnanoflann-dev) rather than PCL's KdTreeFLANN: FLANN enters
// an OpenMP parallel region on every single-point query, which cost ~30 % of DROR's time in
// futex calls (perf), and it cannot stop a count early. nanoflann's result sets can.
#include "worker/mapping/radius_search.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <stdexcept>

namespace keel::mapping {
namespace {

// nanoflann's dataset adaptor over the points, stored in Morton order.
struct PointSet {
  std::vector<Eigen::Vector3f> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(size_t index, size_t axis) const { return points[index][axis]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;  // let nanoflann compute it
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointSet>,
                                                 PointSet, 3, uint32_t>;

// Spreads the low 21 bits of v so that two zero bits separate each (Morton interleaving).
uint64_t spread_bits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

std::vector<uint32_t> morton_order(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3f lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const float extent = std::max((hi - lo).maxCoeff(), 1e-6f);
  const float scale = 2097151.0f / extent;  // 21 bits per axis
  std::vector<std::pair<uint64_t, uint32_t>> keyed(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f cell = (points[i] - lo) * scale;
    keyed[i] = {spread_bits(static_cast<uint64_t>(cell.x())) |
                    spread_bits(static_cast<uint64_t>(cell.y())) << 1 |
                    spread_bits(static_cast<uint64_t>(cell.z())) << 2,
                static_cast<uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> order(points.size());
  for (size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

// Counts points with squared distance < radius^2 and stops the search at `limit`.
class CountResultSet {
 public:
  CountResultSet(float squared_radius, size_t limit)
      : squared_radius_(squared_radius), limit_(limit) {}
  bool addPoint(float squared_distance, uint32_t) {
    if (squared_distance < squared_radius_) ++count_;
    return count_ < limit_;
  }
  float worstDist() const { return squared_radius_; }
  bool full() const { return true; }
  size_t count() const { return count_; }

 private:
  float squared_radius_;
  size_t limit_;
  size_t count_ = 0;
};

// Calls `add(position index)` for every point with squared distance < radius^2.
template <typename Add>
class VisitResultSet {
 public:
  VisitResultSet(float squared_radius, Add add) : squared_radius_(squared_radius), add_(add) {}
  bool addPoint(float squared_distance, uint32_t index) {
    if (squared_distance < squared_radius_) add_(index, squared_distance);
    return true;
  }
  float worstDist() const { return squared_radius_; }
  bool full() const { return true; }

 private:
  float squared_radius_;
  Add add_;
};

const nanoflann::SearchParams kUnsorted(32, 0.0f, false);

}  // namespace

struct RadiusSearch::Impl {
  PointSet set;                 // Morton order
  std::vector<uint32_t> order;  // set.points[i] = input[order[i]]
  static constexpr size_t kLeafSize = 32;
  Tree tree{3, set,
            nanoflann::KDTreeSingleIndexAdaptorParams(
                kLeafSize, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex)};
};

RadiusSearch::RadiusSearch(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()) {
  if (points.size() >= (1ULL << 32)) {
    throw std::invalid_argument("radius search: more than 2^32 points");
  }
  if (points.empty()) return;
  impl_->order = morton_order(points);
  impl_->set.points.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) impl_->set.points[i] = points[impl_->order[i]];
  impl_->tree.buildIndex();
}

RadiusSearch::~RadiusSearch() = default;

size_t RadiusSearch::size() const { return impl_->set.points.size(); }

const std::vector<uint32_t>& RadiusSearch::spatial_order() const { return impl_->order; }

int RadiusSearch::count_within(const Eigen::Vector3f& query, double radius_m, int max_count) const {
  if (impl_->set.points.empty()) return 0;
  const size_t limit = max_count > 0 ? static_cast<size_t>(max_count) : impl_->set.points.size();
  CountResultSet result(static_cast<float>(radius_m * radius_m), limit);
  impl_->tree.findNeighbors(result, query.data(), kUnsorted);
  return static_cast<int>(result.count());
}

void RadiusSearch::within(const Eigen::Vector3f& query, double radius_m, std::vector<int>* indices,
                          std::vector<float>* squared_distances) const {
  indices->clear();
  squared_distances->clear();
  if (impl_->set.points.empty()) return;
  const std::vector<uint32_t>& order = impl_->order;
  auto add = [&](uint32_t i, float d2) {
    indices->push_back(static_cast<int>(order[i]));
    squared_distances->push_back(d2);
  };
  VisitResultSet<decltype(add)> result(static_cast<float>(radius_m * radius_m), add);
  impl_->tree.findNeighbors(result, query.data(), kUnsorted);
}

void RadiusSearch::points_within(const Eigen::Vector3f& query, double radius_m,
                                 std::vector<Eigen::Vector3f>* points) const {
  points->clear();
  if (impl_->set.points.empty()) return;
  const std::vector<Eigen::Vector3f>& stored = impl_->set.points;
  auto add = [&](uint32_t i, float) { points->push_back(stored[i]); };
  VisitResultSet<decltype(add)> result(static_cast<float>(radius_m * radius_m), add);
  impl_->tree.findNeighbors(result, query.data(), kUnsorted);
}

}  // namespace keel::mapping
