// Step 6 of stage `ba`: its section of report.json. One entry per mode: iterations, time, cost,
// the lambda = 1 fraction per iteration (Fig. 16), the DVL range residuals after GICP alone and
// after the mode (Fig. 18), and x_gM against truth.yaml's T_world_cad when the mission has it.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <vector>

#include "core/pose.h"
#include "worker/ba/model_assisted_ba.h"
#include "worker/io/mission.h"
#include "worker/stages/ba/keyframes.h"
#include "worker/stages/ba/options.h"
#include "worker/stages/ba/sensors.h"

namespace keel::pipeline {

// A residual distribution as the report gives it (Fig. 18): count, mean, sigma (the standard
// deviation), robust_sigma (1.4826 x the median absolute deviation from the median), the 5/25/
// 50/75/95 percentiles and a histogram over +-histogram_range_m in histogram_bin_m bins.
nlohmann::json residual_stats(std::vector<double> residuals_m, const BaStageOptions& options);

// truth.yaml's T_world_cad (docs/mission-format.md "Ground truth"); nullopt when the mission has
// no ground truth or it gives none.
std::optional<Pose3> truth_T_world_cad(const io::Mission& mission);

// An estimated model pose against the truth (the report's `T_world_model_vs_truth`): the
// translation error's norm and its components along the true model frame's axes, m, and the
// rotation angle between them, degrees.
nlohmann::json model_error(const Pose3& estimate, const Pose3& truth);

// The report's `input`: where the keyframes, poses, tracks and the CAD mesh came from.
nlohmann::json input_report(const BaKeyframes& keyframes, const BaSensors& sensors,
                            bool frontend_tracks, const std::filesystem::path& cad_mesh);

// The section: `input`, the frontend's, the initialisation's and GICP's figures, every mode,
// the mode the artifacts come from and cad_model.drc's figures.
nlohmann::json ba_report(nlohmann::json input, const ba::BaResult& result,
                         const ba::BaModeResult& artifact_mode, const nlohmann::json& cad_model,
                         const std::optional<Pose3>& truth_T_world_cad,
                         const BaStageOptions& options);

}  // namespace keel::pipeline
