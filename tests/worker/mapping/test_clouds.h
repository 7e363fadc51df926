// Small generators shared by the mapping tests.
#pragma once

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"

namespace keel::mapping::testing {

// Uniform points in the box [lo, hi]^3; intensity holds the point's index (exact below 2^24)
// so tests can tell which points a filter kept.
inline PointCloud random_cloud(size_t n, float lo, float hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  PointCloud cloud;
  for (size_t k = 0; k < n; ++k) {
    cloud.xyz.emplace_back(u(rng), u(rng), u(rng));
    cloud.intensity.push_back(static_cast<float>(k));
  }
  return cloud;
}

// Constant-velocity, constant-yaw-rate motion: slerp/lerp interpolation of it is exact.
inline Pose3 constant_rate_pose(double t_s, const Eigen::Vector3d& v, double yaw_rate,
                                const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ()) {
  return make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rate * t_s, axis.normalized())),
                   v * t_s);
}

inline Trajectory sample_trajectory(double t0_s, double t1_s, double dt_s, const Eigen::Vector3d& v,
                                    double yaw_rate) {
  Trajectory trajectory;
  const long steps = std::lround((t1_s - t0_s) / dt_s);
  for (long i = 0; i <= steps; ++i) {
    const double t = t0_s + i * dt_s;
    trajectory.push_back(StampedPose{std::llround(t * 1e9), constant_rate_pose(t, v, yaw_rate)});
  }
  return trajectory;
}

inline double rotation_angle(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

}  // namespace keel::mapping::testing
