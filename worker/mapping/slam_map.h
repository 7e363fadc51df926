// The "SLAM map" of seed 000 Sec. VI / Table V: the map a keyframe-based lidar SLAM system
// keeps (LIO-SAM, LVI-SAM): each keyframe's scan downsampled by a voxel grid in the sensor
// frame (LIO-SAM's surface/corner leaf is 0.2-0.4 m), placed with that keyframe's pose, and
// the union optionally downsampled again. Built here from the same scans as the inspection map
// so the stage can report both side by side, as Table V does.
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "worker/mapping/deskew.h"
#include "worker/mapping/transform_tree.h"

namespace keel::mapping {

struct SlamMapOptions {
  double keyframe_leaf_m = 0.2;  // voxel leaf of each keyframe scan (LIO-SAM-like)
  double map_leaf_m = 0.0;       // leaf of the union; 0 keeps the union as is
  // A scan stands for keyframe j when its stamp is the closest to t_j within this tolerance.
  double match_tolerance_s = 0.05;
};

class SlamMapBuilder {
 public:
  // `keyframes`: the SLAM system's keyframe poses T_world_body (MAP poses). When `deskew_tree`
  // is given, keyframe scans are motion-compensated with it first (SLAM systems deskew their
  // keyframe clouds too), `sensor` naming the extrinsic in it. Throws std::invalid_argument
  // for unsorted keyframes or bad leaf sizes.
  SlamMapBuilder(const Trajectory& keyframes, const Pose3& T_body_sensor,
                 SlamMapOptions options = {}, const TransformTree* deskew_tree = nullptr,
                 std::string sensor = "");

  // Scans of the SLAM lidar, in its frame, in time order. Keeps at most the best candidate
  // scan of the keyframes not yet passed.
  void add_scan(const PointCloud& scan);
  PointCloud finish();
  size_t keyframes_used() const { return keyframes_used_; }
  size_t keyframes() const { return keyframes_.size(); }

 private:
  struct Candidate {
    TimeNs distance_ns = 0;
    PointCloud scan;
  };
  void commit_until(TimeNs t_ns);
  void commit(size_t keyframe, PointCloud scan);

  Trajectory keyframes_;
  Pose3 T_body_sensor_;
  SlamMapOptions options_;
  const TransformTree* deskew_tree_;
  std::string sensor_;
  TimeNs tolerance_ns_;
  std::map<size_t, Candidate> pending_;
  PointCloud map_;
  size_t keyframes_used_ = 0;
};

}  // namespace keel::mapping
