// The refine stage's self-check, which needs no ground truth: how far the refined keyframes
// moved from the recorded MAP poses, and which moved further than the MAP poses' stated
// uncertainty allows, so a user sees where the refinement disagrees with the recording.
//
// Keyframe k's movement is d_t = p_refined - p_map (world, m) and d_r = Log(R_map^T R_refined)
// (body, rad). Its stated uncertainty is the MAP noise the refinement used (map_pose_noise.h):
// Sigma_t = Sigma_white + Q * s_k (s_k the drift path from the first keyframe, which is the
// gauge: KeyframeEstimate::map_drift_path_m) and Sigma_r. A keyframe is flagged when d_t^T
// Sigma_t^-1 d_t or d_r^T Sigma_r^-1 d_r exceeds `chi2_threshold` (chi-square, 3 degrees of
// freedom).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/pose.h"
#include "worker/slam/map_pose_noise.h"

namespace keel::slam {

// chi^2 with 3 degrees of freedom at 99.73 % (the "3 sigma" of one dimension).
inline constexpr double kChi2ThreeDof9973 = 14.156;

struct KeyframeMovement {
  TimeNs t_ns = 0;
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();  // refined - MAP, world
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();   // Log(R_map^T R_refined), body
  double drift_path_m = 0.0;                                // s_k
  double mahalanobis_translation = 0.0;                     // sqrt(d_t^T Sigma_t^-1 d_t)
  double mahalanobis_rotation = 0.0;
  bool flagged = false;
};

struct MapAgreement {
  std::vector<KeyframeMovement> keyframes;
  double chi2_threshold = kChi2ThreeDof9973;
  int flagged = 0;
  double translation_rms_m = 0.0, translation_max_m = 0.0;
  double rotation_rms_rad = 0.0, rotation_max_rad = 0.0;
};

// `map`, `refined` and `drift_path_m` must hold the same keyframes (stamps). Throws
// std::invalid_argument naming the first mismatch, or for a covariance that is not positive
// definite.
MapAgreement compare_with_map(const Trajectory& map, const Trajectory& refined,
                              const MapPoseNoise& noise, const std::vector<double>& drift_path_m,
                              double chi2_threshold = kChi2ThreeDof9973);

}  // namespace keel::slam
