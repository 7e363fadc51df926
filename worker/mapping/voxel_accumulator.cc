#include "worker/mapping/voxel_accumulator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace keel::mapping {
namespace {

int64_t axis_index(double coordinate, double inverse_leaf) {
  const double scaled = std::floor(coordinate * inverse_leaf);
  // 2^62: keeps neighbouring-index arithmetic (i + 1) and the hash free of overflow.
  constexpr double kLimit = 4.611686018427388e18;
  if (!(std::abs(scaled) < kLimit)) {
    throw std::invalid_argument("voxel grid: coordinate " + std::to_string(coordinate) +
                                " / leaf does not fit a 62-bit voxel index");
  }
  return static_cast<int64_t>(scaled);
}

}  // namespace

VoxelKey voxel_of(const Eigen::Vector3f& p, double inverse_leaf) {
  return VoxelKey{axis_index(p.x(), inverse_leaf), axis_index(p.y(), inverse_leaf),
                  axis_index(p.z(), inverse_leaf)};
}

VoxelAccumulator::VoxelAccumulator(double leaf_m) : leaf_m_(leaf_m), inverse_leaf_(1.0 / leaf_m) {
  if (!std::isfinite(leaf_m) || leaf_m <= 0.0) {
    throw std::invalid_argument("voxel grid: leaf must be a positive number of metres, got " +
                                std::to_string(leaf_m));
  }
}

void VoxelAccumulator::add(const PointCloud& cloud) {
  if (cloud.empty()) return;
  const bool with_intensity = cloud.intensity.size() == cloud.xyz.size();
  intensity_everywhere_ = intensity_everywhere_ && with_intensity;
  if (voxels_.empty()) voxels_.reserve(cloud.size() / 2);
  for (size_t n = 0; n < cloud.xyz.size(); ++n) {
    const Eigen::Vector3f& p = cloud.xyz[n];
    if (!p.allFinite()) {
      throw std::invalid_argument("voxel grid: point " + std::to_string(n) + " is not finite");
    }
    Sum& sum = voxels_[voxel_of(p, inverse_leaf_)];
    sum.xyz += p.cast<double>();
    if (with_intensity) sum.intensity += cloud.intensity[n];
    ++sum.count;
  }
  points_added_ += cloud.size();
}

PointCloud VoxelAccumulator::centroids() const {
  std::vector<std::pair<VoxelKey, const Sum*>> ordered;
  ordered.reserve(voxels_.size());
  for (const auto& [key, sum] : voxels_) ordered.emplace_back(key, &sum);
  std::sort(ordered.begin(), ordered.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  PointCloud out;
  out.xyz.reserve(ordered.size());
  const bool with_intensity = intensity_everywhere_ && points_added_ > 0;
  if (with_intensity) out.intensity.reserve(ordered.size());
  for (const auto& [key, sum] : ordered) {
    const double inverse_count = 1.0 / static_cast<double>(sum->count);
    out.xyz.push_back((sum->xyz * inverse_count).cast<float>());
    if (with_intensity) out.intensity.push_back(static_cast<float>(sum->intensity * inverse_count));
  }
  return out;
}

void VoxelAccumulator::clear() {
  voxels_.clear();
  intensity_everywhere_ = true;
  points_added_ = 0;
}

}  // namespace keel::mapping
