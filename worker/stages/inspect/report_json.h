// Step 4 of stage `inspect`: its section of report.json.
#pragma once

#include <nlohmann/json.hpp>

#include "worker/inspect/inspect.h"
#include "worker/stages/ba/artifacts.h"
#include "worker/stages/inspect/options.h"

namespace keel::pipeline {

// The options, the threshold tau in force (line 6 of Algorithm 1), the counts and times of
// run_inspect, mesh_remeshed.drc's figures (`draco`) and each shape: height, mean deviation,
// centroid, extent, views, landmarks and detections.
nlohmann::json inspect_report(const BaSolution& solution, const inspect::InspectResult& result,
                              const nlohmann::json& draco, const InspectStageOptions& options);

}  // namespace keel::pipeline
