// Step 3 of the compare stage: hulls. Both remeshed hulls come from the same CAD model, so they
// are compared in the model frame (each job's mesh moved back by its own x_gM, hull_survey.h):
// each vertex of B takes the deviation of A's nearest vertex, and the shapes of both
// shapes.json are matched by overlap into changes.json (new, gone, and the growth of each kept
// shape: compare/shape_matching.h).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

// Writes change_hull.drc / .ply and returns the report section (the changes.json document).
nlohmann::json compare_hulls(StageContext& context, const CompareStageOptions& options,
                             std::vector<std::string>* artifacts);

}  // namespace keel::pipeline
