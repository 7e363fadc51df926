// Stage `refine`'s self-check, which needs no ground truth (slam/map_agreement.h): how far the
// refinement moved each keyframe from its MAP pose, against the MAP noise the solve used.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/pose.h"
#include "worker/slam/refine_solver.h"

namespace keel::pipeline {

// Writes refine_self_check.csv (`csv_path`, one row per keyframe) and returns the report's
// `self_check`. `map_poses` are the recorded poses of the keyframes `result` holds.
nlohmann::json self_check(const Trajectory& map_poses, const Trajectory& refined,
                          const slam::RefineResult& result, const std::filesystem::path& csv_path);

}  // namespace keel::pipeline
