// Stage `refine` against ground truth: seed 000's Table II (ATE and RPE of the MAP poses and of
// the refinement without and with DVL, as evo computes them) and trajectories.json.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "core/pose.h"
#include "worker/io/mission.h"
#include "worker/stages/refine/options.h"

namespace keel::pipeline {

// The report's `evaluation`; `without_dvl` and `with_dvl` are null when not solved.
nlohmann::json evaluation_json(const Trajectory& truth, const Trajectory& map_poses,
                               const Trajectory* without_dvl, const Trajectory* with_dvl,
                               const RefineStageOptions& options, const io::Mission& mission);

// Adds to trajectories.json the recorded MAP poses of the keyframes used (Table II's MAP row),
// the written refinement, the one without DVL when both were solved, and the ground truth
// (`truth`, empty when none); each estimate with its per-pose ATE under the report's alignment
// when there is ground truth.
void write_trajectories(const std::filesystem::path& work_dir, const Trajectory& recorded,
                        const Trajectory& refined, const Trajectory* refined_no_dvl,
                        const Trajectory& truth, const RefineStageOptions& options);

}  // namespace keel::pipeline
