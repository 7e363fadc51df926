// True body poses sampled densely (1 kHz) for fast lookups at lidar column times; between
// samples, linear position and slerp (error < 1e-7 m at the speeds simulated here).
#pragma once

#include <vector>

#include "tests/sim/motion.h"
#include "core/pose.h"

namespace keel::sim {

class PoseTable {
 public:
  PoseTable(const PathMotion& motion, double duration_s, double rate_hz = 1000.0);
  Pose3 T_world_body(double t_s) const;
  double duration() const { return duration_s_; }

 private:
  double duration_s_, dt_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Eigen::Quaterniond> rotations_;
};

}  // namespace keel::sim
