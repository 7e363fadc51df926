// Stage `refine`'s report.json section `dvl`: the DVL scale s_d and the DVL-IMU rotation as
// estimated (seed 000 Sec. VII), against truth.yaml when the mission has it, and the DVL gaps
// Algorithm 1 did not bridge.
#pragma once

#include <nlohmann/json.hpp>

#include "worker/io/mission.h"
#include "worker/slam/refine_solver.h"
#include "worker/stages/refine/inputs.h"
#include "worker/stages/refine/options.h"

namespace keel::pipeline {

// `with_dvl` is the solve with DVL fusion; a truth.yaml without a DVL figure adds a warning.
nlohmann::json dvl_report_json(const slam::RefineResult& with_dvl,
                               const RefineStageOptions& options, const io::Mission& mission,
                               Inputs& in);

}  // namespace keel::pipeline
