// RANSAC rigid alignment of two sets of corresponding 3D points (Sec. 2.7, seed 001: stereo
// matches between keyframes must agree with one 6-DOF rigid motion [46, 5]). Minimal
// samples of three points are solved by Umeyama's least-squares fit without scale
// (Eigen::umeyama), the model with most inliers is refit on all of them.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

#include "core/pose.h"

namespace keel::ba {

struct RigidRansacResult {
  Pose3 T_a_b = Pose3::Identity();  // points_a ~ T_a_b * points_b
  std::vector<bool> inliers;
  int num_inliers = 0;
};

// nullopt when there are fewer than three pairs or no sample gives three inliers.
std::optional<RigidRansacResult> rigid_ransac(const std::vector<Eigen::Vector3d>& points_a,
                                              const std::vector<Eigen::Vector3d>& points_b,
                                              double inlier_threshold_m, int iterations,
                                              uint32_t seed = 1);

}  // namespace keel::ba
