// Step 2 of the compare stage: maps. B's maps are registered onto A's on stable structure, then
// every point of each map of B gets its C2C distance to A and the M3C2 change (with its 95 %
// level of detection) of its core point, written as change_<map>.drc / .ply.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "worker/stages/compare/stage.h"

namespace keel::pipeline {

// The maps a job folder holds: "<name>" for every map_<name>.drc (previews left out), sorted.
std::vector<std::string> map_names(const std::filesystem::path& dir);

// The maps to compare: options.sensors, else `combined` when both have it, else every map
// both have. Throws std::runtime_error naming what is missing.
std::vector<std::string> maps_to_compare(const std::vector<std::string>& a,
                                         const std::vector<std::string>& b,
                                         const CompareStageOptions& options);

// Compares the maps, writes their artifacts into context.work_dir (names appended to
// `artifacts`) and returns the report section {"registration": ..., "maps": {name: ...}}.
nlohmann::json compare_maps(StageContext& context, const CompareStageOptions& options,
                            const std::vector<std::string>& maps,
                            std::vector<std::string>* artifacts);

}  // namespace keel::pipeline
