// What an online SLAM system would have recorded during the mission: high-rate, locally
// consistent lidar-inertial odometry that drifts (random walks in yaw and translation, a
// scale error, and, in a corridor, a large error along the degenerate axis), and ~1 Hz
// keyframe MAP poses close to the truth (loop closures keep them in) but worse along the
// degenerate direction (seed 000 Sec. V-D, Fig. 4).
#pragma once

#include <Eigen/Core>

#include "tests/sim/pose_table.h"
#include "core/pose.h"

namespace keel::sim {

struct OdometryOptions {
  double rate_hz = 10.0;
  double scale_sigma = 0.02;                  // constant scale error ~ N(0, 2 %)
  double translation_walk_per_sqrt_m = 0.01;  // m per sqrt(m travelled), each axis
  double yaw_walk_per_sqrt_m = 0.002;         // rad per sqrt(m travelled)
  double yaw_bias_sigma_per_m = 5e-4;         // rad per m, constant per mission
  Eigen::Vector3d degenerate_axis_world = Eigen::Vector3d::Zero();  // zero: none
  double degenerate_gain = -0.4;  // fraction of the motion along the axis that is lost
  double degenerate_gain_sigma = 0.1;
};

struct MapPoseOptions {
  double rate_hz = 1.0;
  double sigma_translation_m = 0.03;
  double sigma_rotation_rad = 0.005;
  Eigen::Vector3d degenerate_axis_world = Eigen::Vector3d::Zero();
  double degenerate_walk_per_sqrt_m = 0.06;  // random walk along the axis, m per sqrt(m)
};

// Poses are stamped t0_ns + k / rate; they start at the true pose.
Trajectory simulate_odometry(const PoseTable& truth, double duration_s, TimeNs t0_ns,
                             const OdometryOptions& options, uint64_t seed);
Trajectory simulate_map_poses(const PoseTable& truth, double duration_s, TimeNs t0_ns,
                              const MapPoseOptions& options, uint64_t seed);

// Root-mean-square position error of `estimate` against `truth` at the estimate's stamps.
double position_rmse(const Trajectory& estimate, const PoseTable& truth, TimeNs t0_ns);

}  // namespace keel::sim
