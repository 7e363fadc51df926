// Camera factors of Sec. 2.6.3-2.6.4, seed 001: stereo (Eq. 12) and monocular (Eq. 13)
// reprojection errors through the chain x_gv_i (+) x_v_i_s_i(theta) (+) x_sc_T, with
// sigma_c = 2 px. Parameters of both: vehicle pose x_gv_i (7), servo angle theta (1),
// extrinsic x_sc_T (7), landmark l_k in the world frame (3).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include "worker/ba/ba_problem.h"
#include "worker/ba/rig_geometry.h"

namespace keel::ba {

// Eq. (13): r = (K [R|t]_cg l_k - z_ik) / sigma_c   (2 residuals).
ceres::CostFunction* make_monocular_factor(const PinholeCamera& camera, const ServoMount& mount,
                                           const Eigen::Vector2d& pixel, double sigma_px);

// Eq. (12): r = ([K_T [R|t]_cT_g l_k ; K_B [R|t]_cB_g l_k] - [z_T ; z_B]) / sigma_c   (4),
// where the bottom camera is x_cT_cB = T_top_bottom from stereo calibration.
ceres::CostFunction* make_stereo_factor(const PinholeCamera& top, const PinholeCamera& bottom,
                                        const Pose3& T_top_bottom, const ServoMount& mount,
                                        const Eigen::Vector2d& pixel_top,
                                        const Eigen::Vector2d& pixel_bottom, double sigma_px);

}  // namespace keel::ba
