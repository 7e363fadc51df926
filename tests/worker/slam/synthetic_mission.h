// A synthetic USV mission for the refine solver's tests and benchmark: a smooth figure-eight
// with waves, IMU and DVL samples generated from it with the noise of seed 000 Table I, a DVL
// scale factor and extrinsic error, and a recorded odometry that drifts and degenerates along
// the body x axis in a corridor segment (the paper's Environment 2 effect).
#pragma once

#include <Eigen/Core>

#include <cstdint>

#include "core/pose.h"
#include "worker/slam/imu_preintegration.h"
#include "worker/slam/refine_solver.h"

namespace keel::slam::testing {

struct SyntheticMissionOptions {
  double duration_s = 120.0;
  double imu_rate_hz = 200.0;
  double dvl_rate_hz = 20.0;
  double keyframe_period_s = 1.0;
  double path_omega_radps = 0.035;  // figure-eight angular frequency (~1.2 m/s peak speed)
  uint64_t seed = 7;

  ImuNoise imu_noise;
  Eigen::Vector3d gyro_bias_radps{2e-4, -1e-4, 3e-4};
  Eigen::Vector3d accel_bias_mps2{0.02, -0.01, 0.015};
  DvlNoise dvl_noise;  // white noise used: hypot(floor, rel |v|) per sample
  Eigen::Vector3d dvl_bias_mps{1e-3, -5e-4, 0.0};  // constant, DVL frame
  double dvl_scale = 1.0;                          // true s_d
  double dvl_dropout_start_s = -1.0;               // < 0: none
  double dvl_dropout_duration_s = 0.0;

  Pose3 T_body_imu = Pose3::Identity();
  Pose3 T_body_dvl_true = Pose3::Identity();
  Pose3 T_body_dvl_nominal = Pose3::Identity();  // what the solver is told

  // Odometry between keyframes: per-edge noise, a slow yaw drift, and a degenerate segment
  // where only a fraction of the body-x motion is seen and the information along x is tiny.
  double odom_sigma_translation_m = 0.03;
  double odom_sigma_rotation_rad = 0.003;
  double odom_yaw_drift_radps = 2e-4;
  double degenerate_start_s = 50.0;  // < 0: none
  double degenerate_duration_s = 20.0;
  double degenerate_x_fraction = 0.6;
  double degenerate_x_information = 1e-2;  // 1/m^2 along body x

  // Loop closures where the true path revisits within this distance after loop_min_gap_s.
  bool loop_closures = false;
  double loop_max_distance_m = 2.0;
  double loop_min_gap_s = 60.0;
  double loop_sigma_translation_m = 0.05;
  double loop_sigma_rotation_rad = 0.005;
};

struct SyntheticMission {
  RefineInput input;                   // keyframes initialised from the odometry
  Trajectory ground_truth;             // true T_world_body at the keyframe stamps
  Trajectory odometry;                 // the drifting odometry at the keyframe stamps
  std::vector<bool> degenerate_truth;  // per keyframe: inside the degenerate segment
};

// The true body pose of the synthetic path at t (s).
Pose3 synthetic_body_pose(double t_s, double omega_radps);

SyntheticMission make_synthetic_mission(const SyntheticMissionOptions& options);

}  // namespace keel::slam::testing
