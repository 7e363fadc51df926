// Step 1 of stage `inspect`: the `ba` stage's solution (ba_solution.json) and the CAD mesh moved
// into the world frame by its x_gM, as the input of keel::inspect::run_inspect.
#pragma once

#include <filesystem>

#include "core/triangle_mesh.h"
#include "worker/inspect/inspect_input.h"
#include "worker/stages/ba/artifacts.h"

namespace keel::pipeline {

// Fails naming the file when it is missing (no `ba` stage ran) or not a ba_solution.json.
BaSolution read_ba_solution(const std::filesystem::path& path);

// The landmarks (with h and lambda), the camera poses and `cad_in_model` moved by x_gM.
inspect::InspectInput inspect_input(const BaSolution& solution, TriangleMesh cad_in_model);

}  // namespace keel::pipeline
