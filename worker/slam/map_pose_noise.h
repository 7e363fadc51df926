// How noisy the recorded MAP keyframe poses are, estimated from the data (beyond the paper).
//
// The online SLAM's keyframe poses come without a covariance. Their position error is modelled
// as white noise plus a drift that random-walks along the path travelled while the scan
// matching was degenerate: there the online system dead reckons along the lost direction and
// its poses walk away from the truth; where it works, loop closures and scan-to-map matching
// keep them within a white scatter. The rotation error is white. The refine solver measures
// the "drift path" over the keyframes whose odometry it finds degenerate (degeneracy.h).
//
// The estimate is a method of moments on the differences of e_k = p_map,k - p_ref,k against a
// reference trajectory whose short-range shape is more accurate than the MAP's (the refinement:
// DVL, IMU and odometry set its shape over a few keyframes, the MAP only its long-range course):
//   E[(e_k - e_{k-m}) (e_k - e_{k-m})^T] = 2 Sigma_white + Q * (s_k - s_{k-m}),
// with s the drift path length, fitted by least squares over the lags m = 1..max_lag. Differences
// cancel whatever offset or slow course error the reference shares with the MAP, so the
// estimate needs no ground truth and no absolute reference.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/pose.h"

namespace keel::slam {

struct MapPoseNoise {
  Eigen::Matrix3d translation_covariance = Eigen::Matrix3d::Zero();  // white, world axes, m^2
  Eigen::Matrix3d drift_covariance_per_m = Eigen::Matrix3d::Zero();  // m^2 per m of path
  Eigen::Matrix3d rotation_covariance = Eigen::Matrix3d::Zero();     // white, body axes, rad^2

  // Isotropic noise: sigma_t (m), sigma_r (rad), drift (m per sqrt(m)).
  static MapPoseNoise isotropic(double sigma_translation_m, double sigma_rotation_rad,
                                double drift_per_sqrt_m);
  // Marginal covariance of a MAP position after `path_m` metres of drift path from the first
  // keyframe, whose pose is the gauge (its drift is zero).
  Eigen::Matrix3d position_covariance(double path_m) const;
};

struct MapNoiseEstimateOptions {
  int max_lag = 5;  // keyframes; ~5 m at 1 m per keyframe
  // Floors of the estimate (standard deviations along each eigen-direction): a floor keeps
  // the anchors' information finite where MAP and reference agree exactly.
  double min_sigma_translation_m = 1e-3;
  double min_sigma_rotation_rad = 1e-4;
  double min_drift_per_sqrt_m = 1e-3;
};

// Path length from the first pose at every pose (positions of `poses`), metres.
std::vector<double> path_lengths(const std::vector<Pose3>& poses);

// Estimates the MAP's noise from `map` and `reference` (same keyframes, same frame; the rotation
// error is Log(R_ref^T R_map)) and each keyframe's drift path s_k (non-decreasing, m). Without
// any spread in s the drift is left at its floor. Needs at least 3 poses; with fewer lags than
// max_lag available, uses those. Throws std::invalid_argument for mismatched sizes or fewer
// than 3 poses.
MapPoseNoise estimate_map_pose_noise(const std::vector<Pose3>& map,
                                     const std::vector<Pose3>& reference,
                                     const std::vector<double>& drift_path_m,
                                     const MapNoiseEstimateOptions& options = {});

}  // namespace keel::slam
