// The TF tree of seed 000 Sec. VI-A2: world W -> body B (time-stamped poses, interpolated) ->
// sensor S_i (static extrinsics T_body_sensor, by sensor name). Queried at a scan's capture
// time it gives T_world_sensor = T_world_body(t) * T_body_sensor.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/mapping/stamped_transforms.h"

namespace keel::mapping {

class TransformTree {
 public:
  // Throws std::invalid_argument as StampedTransforms does.
  explicit TransformTree(const Trajectory& T_world_body, std::string name = "trajectory");

  // Registers (or replaces) a sensor's extrinsic. Throws for a non-rigid or non-finite one.
  void set_extrinsic(const std::string& sensor, const Pose3& T_body_sensor);
  // Throws std::invalid_argument naming the sensor and the known ones when it is unknown.
  const Pose3& T_body_sensor(const std::string& sensor) const;
  std::vector<std::string> sensors() const;

  // Both throw std::out_of_range naming the time and the covered span outside the trajectory.
  Pose3 T_world_body(TimeNs t_ns) const { return poses_.at(t_ns); }
  Pose3 T_world_sensor(const std::string& sensor, TimeNs t_ns) const;

  const StampedTransforms& body_poses() const { return poses_; }
  bool covers(TimeNs t_ns) const { return poses_.covers(t_ns); }
  TimeNs begin_ns() const { return poses_.begin_ns(); }
  TimeNs end_ns() const { return poses_.end_ns(); }

 private:
  StampedTransforms poses_;
  std::map<std::string, Pose3> T_body_sensor_;
};

}  // namespace keel::mapping
