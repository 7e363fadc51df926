// Shared checks of a stage's JSON options (`--set stage.option=value`).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace keel::pipeline {

// "a, b, c": for messages that list what is known.
std::string join_names(const std::vector<std::string>& names);

// Checks that `options` is null or an object whose keys are all in `known`; a typo fails
// with "options.<stage>.<key>: unknown option (known: ...)" instead of being ignored.
void check_stage_options(const nlohmann::json& options, const std::string& stage,
                         const std::vector<std::string>& known);

}  // namespace keel::pipeline
