#include "worker/mapping/radius_search.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace keel::mapping {

struct RadiusSearch::Impl {
  // Unsorted results: radiusSearch is faster and no caller needs the order.
  pcl::KdTreeFLANN<pcl::PointXYZ> tree{false};
  size_t size = 0;
};

RadiusSearch::RadiusSearch(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()) {
  impl_->size = points.size();
  if (points.empty()) return;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->resize(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    (*cloud)[k].getVector3fMap() = points[k];
  }
  cloud->is_dense = true;
  impl_->tree.setInputCloud(cloud);
}

RadiusSearch::~RadiusSearch() = default;

size_t RadiusSearch::size() const { return impl_->size; }

int RadiusSearch::count_within(const Eigen::Vector3f& query, double radius_m,
                               int max_count) const {
  if (impl_->size == 0) return 0;
  pcl::PointXYZ point;
  point.getVector3fMap() = query;
  // Reused per thread: count queries run millions of times.
  thread_local pcl::Indices indices;
  thread_local std::vector<float> squared_distances;
  return impl_->tree.radiusSearch(point, radius_m, indices, squared_distances,
                                  max_count > 0 ? static_cast<unsigned>(max_count) : 0);
}

void RadiusSearch::within(const Eigen::Vector3f& query, double radius_m,
                          std::vector<int>* indices, std::vector<float>* squared_distances) const {
  indices->clear();
  squared_distances->clear();
  if (impl_->size == 0) return;
  pcl::PointXYZ point;
  point.getVector3fMap() = query;
  impl_->tree.radiusSearch(point, radius_m, *indices, *squared_distances, 0);
}

}  // namespace keel::mapping
