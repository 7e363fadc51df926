// Step 2 of the compare stage: maps. B's maps are registered onto A's on stable structure
// (map_alignment.h), then every point of each map of B gets its C2C distance to A and the M3C2
// change (with its 95 % level of detection) of its core point, written as change_<map>.drc /
// .ply (map_change.h).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

// Compares the maps, writes their artifacts into context.work_dir (names appended to
// `artifacts`) and returns the report section {"registration": ..., "maps": {name: ...}}.
nlohmann::json compare_maps(StageContext& context, const CompareStageOptions& options,
                            const std::vector<std::string>& maps,
                            std::vector<std::string>* artifacts);

}  // namespace keel::pipeline
