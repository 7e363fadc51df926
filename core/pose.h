// Rigid transforms and stamped poses. T_a_b maps points in frame b into frame a.
#pragma once

#include <Eigen/Geometry>

#include <vector>

#include "core/time.h"

namespace keel {

using Pose3 = Eigen::Isometry3d;

struct StampedPose {
  TimeNs t_ns = 0;
  Pose3 T_world_body = Pose3::Identity();
};

using Trajectory = std::vector<StampedPose>;  // strictly increasing t_ns

inline Pose3 make_pose(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace keel
