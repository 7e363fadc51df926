#include "worker/mapping/slam_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/filters.h"
#include "worker/mapping/stamped_transforms.h"

namespace keel::mapping {

SlamMapBuilder::SlamMapBuilder(const Trajectory& keyframes, const Pose3& T_body_sensor,
                               SlamMapOptions options, const TransformTree* deskew_tree,
                               std::string sensor)
    : keyframes_(keyframes),
      T_body_sensor_(T_body_sensor),
      options_(options),
      deskew_tree_(deskew_tree),
      sensor_(std::move(sensor)),
      tolerance_ns_(seconds_to_ns(options.match_tolerance_s)) {
  StampedTransforms check(keyframes_, "SLAM keyframes");  // validates order and values
  if (!(options_.keyframe_leaf_m > 0.0) || !(options_.map_leaf_m >= 0.0) ||
      !(options_.match_tolerance_s >= 0.0)) {
    throw std::invalid_argument(
        "SLAM map: keyframe_leaf_m must be > 0, map_leaf_m and match_tolerance_s >= 0");
  }
}

void SlamMapBuilder::add_scan(const PointCloud& scan) {
  commit_until(scan.t_ns);
  // The keyframe nearest to the scan stamp.
  const auto upper =
      std::lower_bound(keyframes_.begin(), keyframes_.end(), scan.t_ns,
                       [](const StampedPose& pose, TimeNs t) { return pose.t_ns < t; });
  size_t nearest = static_cast<size_t>(upper - keyframes_.begin());
  if (nearest == keyframes_.size() || (nearest > 0 && scan.t_ns - keyframes_[nearest - 1].t_ns <
                                                          keyframes_[nearest].t_ns - scan.t_ns)) {
    --nearest;
  }
  const TimeNs distance_ns = std::abs(scan.t_ns - keyframes_[nearest].t_ns);
  if (distance_ns > tolerance_ns_) return;
  const auto found = pending_.find(nearest);
  if (found != pending_.end() && found->second.distance_ns <= distance_ns) return;
  pending_[nearest] = Candidate{distance_ns, scan};
}

void SlamMapBuilder::commit_until(TimeNs t_ns) {
  // With scans in time order, no later scan can be closer to a keyframe already passed by
  // more than the tolerance.
  while (!pending_.empty() && keyframes_[pending_.begin()->first].t_ns + tolerance_ns_ < t_ns) {
    commit(pending_.begin()->first, std::move(pending_.begin()->second.scan));
    pending_.erase(pending_.begin());
  }
}

void SlamMapBuilder::commit(size_t keyframe, PointCloud scan) {
  remove_non_finite(scan);
  if (deskew_tree_ != nullptr) {
    try {
      deskew_scan(*deskew_tree_, sensor_, scan);
    } catch (const std::out_of_range&) {
      // Outside the refined trajectory: keep the scan as recorded, as the SLAM system had it.
    }
  }
  scan.time_s.clear();
  apply_voxel_grid(VoxelGridFilter{options_.keyframe_leaf_m}, scan);
  transform_points(scan, keyframes_[keyframe].T_world_body * T_body_sensor_);
  append_points(map_, scan);
  ++keyframes_used_;
}

PointCloud SlamMapBuilder::finish() {
  commit_until(std::numeric_limits<TimeNs>::max());
  PointCloud map = std::move(map_);
  map_ = PointCloud{};
  if (options_.map_leaf_m > 0.0) apply_voxel_grid(VoxelGridFilter{options_.map_leaf_m}, map);
  map.frame = "world";
  return map;
}

}  // namespace keel::mapping
