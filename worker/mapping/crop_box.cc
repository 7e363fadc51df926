// CropBox of Table III, seed 000.
#include <cstdint>
#include <vector>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/filters.h"

namespace keel::mapping {

size_t apply_crop_box(const CropBoxFilter& filter, PointCloud& cloud) {
  const Eigen::Vector3f min_m = filter.min_m.cast<float>();
  const Eigen::Vector3f max_m = filter.max_m.cast<float>();
  std::vector<uint8_t> keep(cloud.size());
  for (size_t n = 0; n < cloud.size(); ++n) {
    const Eigen::Vector3f& p = cloud.xyz[n];
    // Inclusive bounds, as pcl::CropBox tests them.
    const bool inside = (p.array() >= min_m.array()).all() && (p.array() <= max_m.array()).all();
    keep[n] = static_cast<uint8_t>(inside != filter.remove_inside);
  }
  return keep_points(cloud, keep);
}

}  // namespace keel::mapping
