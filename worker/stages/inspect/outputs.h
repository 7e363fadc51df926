// Step 3 of stage `inspect`: the remeshed hull with its per-vertex deviation (Draco, and PLY
// unless write_ply is false) and shapes.json, in the world frame.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "worker/inspect/inspect.h"
#include "worker/stages/inspect/options.h"

namespace keel::pipeline {

struct InspectArtifacts {
  std::vector<std::string> files;  // written into the work folder
  nlohmann::json draco;            // the report's `draco`: mesh_remeshed.drc's size and error
};

InspectArtifacts write_inspect_artifacts(const std::filesystem::path& work_dir,
                                         const inspect::InspectResult& result,
                                         const InspectStageOptions& options);

}  // namespace keel::pipeline
