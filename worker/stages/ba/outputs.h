// Step 6 of stage `ba`: its artifacts (artifacts.h names those other stages read), written from
// one mode's solution.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "worker/ba/model_assisted_ba.h"
#include "worker/stages/ba/options.h"

namespace keel::pipeline {

// The mode the artifacts come from: `proposed` when it ran, else the last mode run.
const ba::BaModeResult& artifact_mode(const ba::BaResult& result);

struct BaArtifacts {
  std::vector<std::string> files;  // written into the work folder, in the report's order
  nlohmann::json cad_model;        // the report's `cad_model`: cad_model.drc's size and error
};

// trajectory_ba.tum (keyframe poses, world), ba_solution.json, dvl_residuals.csv, the `ba`
// trajectory of trajectories.json (model frame) and cad_model.drc with its sidecar.
BaArtifacts write_ba_artifacts(const std::filesystem::path& work_dir, const ba::BaModeResult& mode,
                               const ba::BaProblem& problem, const BaStageOptions& options);

}  // namespace keel::pipeline
