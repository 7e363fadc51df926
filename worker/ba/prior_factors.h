// Prior factors of Sec. 2.6.1, seed 001 (Eq. 8-10). All residuals are whitened.
#pragma once

#include <ceres/cost_function.h>

#include "worker/ba/ba_problem.h"
#include "core/pose.h"

namespace keel::ba {

// Eq. (8): full-state prior N(x_prior, Sigma) on a pose block (pose_block.h layout), with
// Sigma = diag(sigma_rad^2 I_3, sigma_m^2 I_3). Residual (6):
//   r = [ Log(R_prior^-1 R) / sigma_rad ; (t - t_prior) / sigma_m ].
ceres::CostFunction* make_pose_prior_factor(const Pose3& prior, double sigma_m, double sigma_rad);

// Eq. (9): depth, pitch and roll of a vehicle pose (ba_problem.h: DepthPitchRoll).
// Residual (3): [ (z - z_m) / sigma_z ; wrap(pitch - pitch_m) / sigma_pitch ;
//                 wrap(roll - roll_m) / sigma_roll ].
ceres::CostFunction* make_depth_pitch_roll_factor(const DepthPitchRoll& measured, double sigma_m,
                                                  double sigma_pitch_rad, double sigma_roll_rad);

// Eq. (10): servo angle, r = (theta - z_theta) / sigma (1 residual, 1 parameter).
ceres::CostFunction* make_servo_angle_factor(double measured_rad, double sigma_rad);

// Z-Y-X Euler pitch and roll of a rotation (as Eq. 9 measures them) and the world z.
DepthPitchRoll depth_pitch_roll_of(const Pose3& T_world_vehicle);

}  // namespace keel::ba
