// Odometry factor of Sec. 2.6.2, seed 001 (Eq. 11): the relative pose (-)x_gi (+) x_g(i+1)
// observed with a diagonal covariance whose standard deviations grow with the time between
// the keyframes (5 mm/s in translation, 80 deg/h in rotation by default).
#pragma once

#include <ceres/cost_function.h>

#include "core/pose.h"

namespace keel::ba {

struct OdometrySigmas {
  double sigma_m = 0;
  double sigma_rad = 0;
};

// sigma = max(rate * dt, floor) for translation and rotation; dt_s must be > 0.
OdometrySigmas odometry_sigmas(double dt_s, double sigma_m_per_s, double sigma_rad_per_s,
                               double min_sigma_m, double min_sigma_rad);

// Parameters: pose_i, pose_j (pose_block.h). With E = T_i_j_measured^-1 * x_gi^-1 * x_gj,
//   r = [ Log(R_E) / sigma_rad ; t_E / sigma_m ]   (6).
ceres::CostFunction* make_odometry_factor(const Pose3& T_i_j_measured,
                                          const OdometrySigmas& sigmas);

}  // namespace keel::ba
