// A time series of rigid transforms with interpolation at any time inside its span: slerp for
// the rotation (seed 000 ref. [47], Shoemake 1985), linear for the translation, as tf [46]
// does. Unlike tf's 10 s (or MapBuilder's 1000 s) cache there is no length limit: lookups are
// a binary search over the sorted stamps. Times outside the span are an error, never an
// extrapolation.
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "core/pose.h"

namespace keel::mapping {

// Slerp of the rotation, lerp of the translation; s = 0 gives T_a, s = 1 gives T_b.
Pose3 interpolate_pose(const Pose3& T_a, const Pose3& T_b, double s);

class StampedTransforms {
 public:
  // `samples[i].T_world_body` is the transform at `samples[i].t_ns` (for odometry corrections
  // it holds T_world_odom). Throws std::invalid_argument naming `name` and the index for an
  // empty series, unsorted or duplicate stamps, or non-finite / non-rotation entries.
  explicit StampedTransforms(const Trajectory& samples, std::string name = "trajectory");

  // Throws std::out_of_range naming the time and the covered span when t_ns is outside it.
  Pose3 at(TimeNs t_ns) const;
  // As at(), but times before the first / after the last stamp give the first / last sample.
  Pose3 at_clamped(TimeNs t_ns) const;
  bool covers(TimeNs t_ns) const { return t_ns >= stamps_.front() && t_ns <= stamps_.back(); }

  TimeNs begin_ns() const { return stamps_.front(); }
  TimeNs end_ns() const { return stamps_.back(); }
  size_t size() const { return stamps_.size(); }
  const std::vector<TimeNs>& stamps() const { return stamps_; }
  Pose3 sample(size_t i) const;
  const std::string& name() const { return name_; }

 private:
  Pose3 interpolate_inside(TimeNs t_ns) const;

  std::string name_;
  std::vector<TimeNs> stamps_;
  std::vector<Eigen::Quaterniond> rotations_;
  std::vector<Eigen::Vector3d> translations_;
};

}  // namespace keel::mapping
