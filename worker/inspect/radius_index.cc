#include "worker/inspect/radius_index.h"

#include <CGAL/Fuzzy_sphere.h>
#include <CGAL/Kd_tree.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <string>

namespace keel::inspect {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;  // the tree only orders coordinates
using Point = Kernel::Point_3;

// Maps a point index to its coordinates, so the tree stores indices.
class IndexToPoint {
 public:
  using value_type = Point;
  using reference = const Point&;
  using key_type = std::size_t;
  using category = boost::readable_property_map_tag;

  explicit IndexToPoint(const std::vector<Point>* points = nullptr) : points_(points) {}
  friend reference get(const IndexToPoint& map, key_type i) { return (*map.points_)[i]; }

 private:
  const std::vector<Point>* points_;
};

using Traits =
    CGAL::Search_traits_adapter<std::size_t, IndexToPoint, CGAL::Search_traits_3<Kernel>>;
using Tree = CGAL::Kd_tree<Traits>;
using Sphere = CGAL::Fuzzy_sphere<Traits>;

}  // namespace

struct RadiusIndex::Impl {
  std::vector<Eigen::Vector3d> points;
  std::vector<Point> cgal_points;
  std::unique_ptr<Tree> tree;
};

RadiusIndex::RadiusIndex(const std::vector<Eigen::Vector3d>& points)
    : impl_(std::make_unique<Impl>()) {
  impl_->points = points;
  impl_->cgal_points.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    if (!p.allFinite()) {
      throw std::invalid_argument("RadiusIndex: point " + std::to_string(i) +
                                  " is not finite; expected finite coordinates");
    }
    impl_->cgal_points.emplace_back(p.x(), p.y(), p.z());
  }
  impl_->tree =
      std::make_unique<Tree>(boost::counting_iterator<std::size_t>(0),
                             boost::counting_iterator<std::size_t>(impl_->cgal_points.size()),
                             Tree::Splitter(), Traits(IndexToPoint(&impl_->cgal_points)));
  impl_->tree->build();  // built now: a lazy build on the first query would race
}

RadiusIndex::~RadiusIndex() = default;
RadiusIndex::RadiusIndex(RadiusIndex&&) noexcept = default;
RadiusIndex& RadiusIndex::operator=(RadiusIndex&&) noexcept = default;

void RadiusIndex::within(const Eigen::Vector3d& query, double radius_m,
                         std::vector<int>* indices) const {
  indices->clear();
  if (impl_->points.empty()) return;
  // A slightly larger candidate sphere: CGAL's boundary tests mix < and <=, and the exact
  // closed-ball test below must see every point on the boundary.
  const double candidate_radius = radius_m * (1.0 + 1e-9) + 1e-12;
  std::vector<std::size_t> candidates;
  impl_->tree->search(
      std::back_inserter(candidates),
      Sphere(Point(query.x(), query.y(), query.z()), candidate_radius, 0.0, impl_->tree->traits()));
  const double radius_sq = radius_m * radius_m;
  for (const std::size_t i : candidates) {
    if ((impl_->points[i] - query).squaredNorm() <= radius_sq) {
      indices->push_back(static_cast<int>(i));
    }
  }
  std::sort(indices->begin(), indices->end());
}

size_t RadiusIndex::size() const { return impl_->points.size(); }

}  // namespace keel::inspect
