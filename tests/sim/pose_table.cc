#include "tests/sim/pose_table.h"

#include <algorithm>
#include <cmath>

namespace keel::sim {

PoseTable::PoseTable(const PathMotion& motion, double duration_s, double rate_hz)
    : duration_s_(duration_s), dt_(1.0 / rate_hz) {
  const int n = static_cast<int>(std::ceil(duration_s * rate_hz)) + 2;
  positions_.reserve(n);
  rotations_.reserve(n);
  for (int i = 0; i < n; ++i) {
    const KinematicState s = motion.state(i * dt_);
    positions_.push_back(s.p_world);
    rotations_.push_back(s.q_world_body);
  }
}

Pose3 PoseTable::T_world_body(double t_s) const {
  const double x = std::clamp(t_s / dt_, 0.0, double(positions_.size() - 1));
  const size_t i = std::min(static_cast<size_t>(x), positions_.size() - 2);
  const double w = x - double(i);
  Pose3 T = Pose3::Identity();
  T.linear() = rotations_[i].slerp(w, rotations_[i + 1]).toRotationMatrix();
  T.translation() = (1.0 - w) * positions_[i] + w * positions_[i + 1];
  return T;
}

}  // namespace keel::sim
