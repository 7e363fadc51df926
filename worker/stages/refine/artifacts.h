// What the `refine` stage writes that other stages read: the refined keyframe trajectory (TUM),
// which `map` and `ba` start from when refine ran.
#pragma once

#include <string>

namespace keel::pipeline {

inline constexpr const char* kRefinedTrajectoryFile = "trajectory_refined.tum";
// The self-check per keyframe: movement from the MAP pose and whether it exceeds the MAP
// pose's stated uncertainty (slam::compare_with_map).
inline constexpr const char* kSelfCheckFile = "refine_self_check.csv";

}  // namespace keel::pipeline
