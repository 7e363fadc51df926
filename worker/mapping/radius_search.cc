// nanoflann (header-only, Debian libnanoflann-dev) rather than PCL's KdTreeFLANN: FLANN enters
// an OpenMP parallel region on every single-point query, which cost ~30 % of DROR's time in
// futex calls (perf), and it cannot stop a count early. nanoflann's result sets can.
#include "worker/mapping/radius_search.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "worker/mapping/kd_points.h"

namespace keel::mapping {
namespace {

using PointSet = KdPoints;  // stored in Morton order
using Tree = KdTree;

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

// Below this many points (a single scan: ~8k for a VLP-16 sweep) the cloud fits in L2 and the
// Morton sort cost more than the cache misses it saves: 15 % of DROR's time on keel-sim scans
// (perf). Such clouds keep their input order (a scan's acquisition order is coherent too).
constexpr size_t kMortonMinPoints = size_t{1} << 16;

// The first rank of every leaf (leaves partition the tree's index array into ranges).
void collect_leaves(const Tree::Node* node, std::vector<uint32_t>* begins) {
  if (node == nullptr) return;
  if (node->child1 == nullptr && node->child2 == nullptr) {
    begins->push_back(static_cast<uint32_t>(node->node_type.lr.left));
    return;
  }
  collect_leaves(node->child1, begins);
  collect_leaves(node->child2, begins);
}

}  // namespace

struct RadiusSearch::Impl {
  PointSet set;                                // Morton order
  std::vector<uint32_t> order;                 // set.points[i] = input[order[i]]
  std::vector<uint32_t> query_order;           // input indices in the tree's leaf order (by rank)
  std::vector<Eigen::Vector3f> ranked_points;  // ranked_points[rank] = input[query_order[rank]]
  std::vector<float> ranked_x, ranked_y, ranked_z;  // the same, one array per axis
  std::vector<uint32_t> leaf_begin;  // leaf l holds ranks [leaf_begin[l], leaf_begin[l + 1])
  std::vector<uint32_t> leaf_of_rank;
  static constexpr size_t kLeafSize = 64;
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
  if (points.size() >= kMortonMinPoints) {
    impl_->order = morton_order(points);
  } else {
    impl_->order.resize(points.size());
    std::iota(impl_->order.begin(), impl_->order.end(), 0u);
  }
  impl_->set.points.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) impl_->set.points[i] = points[impl_->order[i]];
  impl_->tree.buildIndex();
  // The tree's leaf sequence is a spatial order of its own: queries issued leaf by leaf walk
  // the same nodes one after another.
  const std::vector<uint32_t>& leaves = impl_->tree.vAcc;
  impl_->query_order.resize(leaves.size());
  impl_->ranked_points.resize(leaves.size());
  for (size_t i = 0; i < leaves.size(); ++i) {
    impl_->query_order[i] = impl_->order[leaves[i]];
    impl_->ranked_points[i] = impl_->set.points[leaves[i]];
  }
  impl_->ranked_x.resize(leaves.size());
  impl_->ranked_y.resize(leaves.size());
  impl_->ranked_z.resize(leaves.size());
  for (size_t i = 0; i < leaves.size(); ++i) {
    impl_->ranked_x[i] = impl_->ranked_points[i].x();
    impl_->ranked_y[i] = impl_->ranked_points[i].y();
    impl_->ranked_z[i] = impl_->ranked_points[i].z();
  }
  collect_leaves(impl_->tree.root_node, &impl_->leaf_begin);
  std::sort(impl_->leaf_begin.begin(), impl_->leaf_begin.end());
  impl_->leaf_begin.push_back(static_cast<uint32_t>(leaves.size()));
  impl_->leaf_of_rank.resize(leaves.size());
  for (size_t l = 0; l + 1 < impl_->leaf_begin.size(); ++l) {
    for (uint32_t r = impl_->leaf_begin[l]; r < impl_->leaf_begin[l + 1]; ++r) {
      impl_->leaf_of_rank[r] = static_cast<uint32_t>(l);
    }
  }
}

RadiusSearch::~RadiusSearch() = default;

size_t RadiusSearch::size() const { return impl_->set.points.size(); }

const std::vector<uint32_t>& RadiusSearch::spatial_order() const { return impl_->query_order; }

int RadiusSearch::count_within(const Eigen::Vector3f& query, double radius_m, int max_count) const {
  if (impl_->set.points.empty()) return 0;
  const size_t limit = max_count > 0 ? static_cast<size_t>(max_count) : impl_->set.points.size();
  CountResultSet result(static_cast<float>(radius_m * radius_m), limit);
  impl_->tree.findNeighbors(result, query.data(), kUnsorted);
  return static_cast<int>(result.count());
}

int RadiusSearch::count_around(size_t rank, double radius_m, int max_count) const {
  const Impl& impl = *impl_;
  const Eigen::Vector3f& query = impl.ranked_points[rank];
  const float squared_radius = static_cast<float>(radius_m * radius_m);
  const uint32_t leaf = impl.leaf_of_rank[rank];
  // The point's own leaf first: its neighbours are usually there, and once max_count of them
  // are the answer is exact without descending the tree. Branch-free over SoA coordinates
  // (vectorised); same float arithmetic as L2_Simple_Adaptor: ((dx^2 + dy^2) + dz^2) < r^2.
  const float* x = impl.ranked_x.data();
  const float* y = impl.ranked_y.data();
  const float* z = impl.ranked_z.data();
  const float qx = query.x(), qy = query.y(), qz = query.z();
  int count = 0;
  for (uint32_t j = impl.leaf_begin[leaf]; j < impl.leaf_begin[leaf + 1]; ++j) {
    const float dx = qx - x[j], dy = qy - y[j], dz = qz - z[j];
    count += dx * dx + dy * dy + dz * dz < squared_radius;
  }
  if (count >= max_count) return max_count;
  return count_within(query, radius_m, max_count);
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

}  // namespace keel::mapping
