// Odometry noise estimated per mission from the recorded MAP poses (beyond seed 000): the
// odometry increments' disagreement with the MAP poses' increments is a variance the fixed
// noise model does not know of, so an odometry that degenerated (a corridor) or whose
// information is over-confident (GICP's point-to-plane Hessian treats neighbouring residuals as
// independent) stops outvoting the DVL.
//
// Edge k's disagreement is e_k = [t_odo - t_map, Log(R_map^T R_odo)] (the frame of keyframe k,
// m and rad); rms = sqrt(mean_k e_k^2) per axis over the edges that carry information. Every
// edge's covariance becomes Sigma' = Sigma + D, D = diag(rms^2), its information computed as
// D^-1/2 M (I + M)^-1 D^-1/2 with M = D^1/2 Information D^1/2: no inverse of the (possibly
// singular) information, and its correlations kept (GICP's information couples translation
// with roll and pitch through the lidar's lever arm). For a diagonal information this is
// 1 / (1 / information + rms^2) per axis.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <vector>

#include "core/pose.h"
#include "worker/slam/relative_pose.h"

namespace keel::slam {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// The per-axis RMS of e_k, [translation (m), rotation (rad)], over the edges k -> k+1 whose
// information is not zero; nullopt unless `odometry` holds one edge per consecutive keyframes
// and one of them carries information.
std::optional<Vector6d> odometry_disagreement_rms(
    const Trajectory& keyframes, const std::vector<RelativePoseMeasurement>& odometry);

// The information of Sigma + diag(sigma_added^2), Sigma the covariance `information` stands
// for (zero eigenvalues stay zero); sigma_added is floored at 1e-6 (1 um, 1 urad) so D stays
// invertible when an axis agrees exactly.
Matrix6d widen_information(const Matrix6d& information, const Vector6d& sigma_added);

// Widens every edge of `odometry` by its disagreement with `keyframes` (the above); returns
// the RMS used, or nullopt (and leaves the edges as they are) when there is none.
std::optional<Vector6d> widen_by_map_disagreement(const Trajectory& keyframes,
                                                  std::vector<RelativePoseMeasurement>& odometry);

}  // namespace keel::slam
