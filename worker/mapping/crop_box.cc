// CropBox of Table III, seed 000.
#include <cstdint>
#include <vector>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/filters.h"

namespace keel::mapping {

std::vector<uint8_t> crop_box_keep(const CropBoxFilter& filter,
                                   const std::vector<Eigen::Vector3f>& points) {
  const Eigen::Vector3f min_m = filter.min_m.cast<float>();
  const Eigen::Vector3f max_m = filter.max_m.cast<float>();
  std::vector<uint8_t> keep(points.size());
  for (size_t n = 0; n < points.size(); ++n) {
    const Eigen::Vector3f& p = points[n];
    // Inclusive bounds, as pcl::CropBox tests them.
    const bool inside = (p.array() >= min_m.array()).all() && (p.array() <= max_m.array()).all();
    keep[n] = static_cast<uint8_t>(inside != filter.remove_inside);
  }
  return keep;
}

size_t apply_crop_box(const CropBoxFilter& filter, PointCloud& cloud) {
  return keep_points(cloud, crop_box_keep(filter, cloud.xyz));
}

}  // namespace keel::mapping
