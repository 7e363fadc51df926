// Internal to refine_solver.cc, steps 1-2 of refine_trajectory: the keyframes' checks and the
// relative-pose constraints between keyframes (odometry with its degeneracy, loop closures),
// matched to keyframes by stamp and expressed in the IMU frame.
#pragma once

#include <string>
#include <vector>

#include "core/pose.h"
#include "core/time.h"
#include "worker/slam/refine_solver.h"
#include "worker/slam/relative_pose.h"

namespace keel::slam {

// A relative-pose constraint between keyframe indices, in the IMU frame.
struct KeyframeEdge {
  int i = 0, j = 0;
  Pose3 T_i_j = Pose3::Identity();
  Matrix6d sqrt_info = Matrix6d::Zero();
};

// Throws std::invalid_argument naming the keyframe: fewer than 2, a pose not finite, a stamp not
// after the previous one.
void validate_keyframes(const Trajectory& keyframes);

// Odometry edges (none unless opt.use_odometry); marks each edge's later keyframe in `kf` with
// the edge's degeneracy (Sec. IV-B) and drops or trims degenerate edges as
// opt.degeneracy_handling says. Throws naming the measurement when a stamp matches no keyframe.
std::vector<KeyframeEdge> odometry_edges(const RefineInput& in, const RefineOptions& opt,
                                         const std::vector<TimeNs>& t_ns,
                                         std::vector<KeyframeEstimate>* kf);
// Loop closure edges (none unless opt.use_loop_closures); throws as above.
std::vector<KeyframeEdge> loop_edges(const RefineInput& in, const RefineOptions& opt,
                                     const std::vector<TimeNs>& t_ns);

}  // namespace keel::slam
