// Step 4 of the compare stage: two runs side by side (a reprocess of the same mission with
// other options, or two surveys): every number of both report.json files with its difference,
// the options that differ, and the relative ATE of their trajectories.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "worker/pipeline/stage.h"

namespace keel::pipeline {

// "path" -> number for every number of `document` that is not inside an array, paths joined
// with '.' (arrays are distributions and histograms, summarised elsewhere).
void flatten_numbers(const nlohmann::json& document, const std::string& prefix,
                     std::vector<std::pair<std::string, double>>* out);

// The options that differ between two jobs' {"stage": {"option": value}} objects:
// [{"option": "map.metrics_radius_m", "a": 0.25, "b": 0.3}], absent values as null.
nlohmann::json options_difference(const nlohmann::json& a, const nlohmann::json& b);

// Reads report.json (and the trajectories) of both input jobs; `max_figures` bounds the list.
nlohmann::json compare_runs(const InputJob& a, const InputJob& b, size_t max_figures = 5000);

}  // namespace keel::pipeline
