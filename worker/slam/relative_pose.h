// Relative-pose measurements between keyframes (odometry edges, loop closures) and how to get
// them from a recorded odometry trajectory.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/pose.h"
#include "core/time.h"

namespace keel::slam {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// T_i_j = T_world_body(t_i)^-1 * T_world_body(t_j), with information in the tangent order
// [translation, rotation]: t = t_ij + delta t, R = R_ij Exp(delta phi) (relative_pose_factor.h).
struct RelativePoseMeasurement {
  TimeNs t_i_ns = 0;
  TimeNs t_j_ns = 0;
  Pose3 T_i_j = Pose3::Identity();
  Matrix6d information = Matrix6d::Identity();
};

// The information of independent errors with the same sigma on every translation axis (m) and
// on every rotation axis (rad): diag(1/sigma_t^2 I_3, 1/sigma_r^2 I_3).
Matrix6d isotropic_information(double sigma_translation_m, double sigma_rotation_rad);

// Default noise of a recorded odometry increment, which carries no covariance of its own:
// sigma = base + per_metre * |t_ij| (and + per_radian * |phi_ij| for rotation). Not in the
// paper (LVI-SAM takes its covariances from scan matching); an engineering choice for a
// lidar-inertial odometry that drifts ~1% of distance travelled.
struct OdometryNoise {
  double sigma_translation_m = 0.02;
  double sigma_translation_per_m = 0.01;
  double sigma_rotation_rad = 0.002;
  double sigma_rotation_per_rad = 0.01;
  double sigma_rotation_per_m = 0.001;

  Matrix6d information(const Pose3& T_i_j) const;
};

// Pose of `trajectory` at t_ns: linear in translation, SLERP in rotation. Throws
// std::out_of_range when t_ns lies outside the trajectory.
Pose3 interpolate_pose(const Trajectory& trajectory, TimeNs t_ns);

// Odometry edges between consecutive keyframes, interpolating `odometry` at the keyframe
// stamps. `information` (optional, one per keyframe k >= 1, for the edge k-1 -> k) replaces
// the default noise, e.g. the Hessian of the scan matching that produced the odometry, which
// is what degeneracy detection looks at. Throws std::invalid_argument naming the problem
// (unsorted stamps, keyframes outside the odometry, wrong information count).
std::vector<RelativePoseMeasurement> relative_poses_from_trajectory(
    const Trajectory& odometry, const std::vector<TimeNs>& keyframe_t_ns,
    const OdometryNoise& noise = {}, const std::vector<Matrix6d>& information = {});

}  // namespace keel::slam
