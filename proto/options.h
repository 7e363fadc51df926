// Pipeline options: {"stage": {"option": value}} as given by `--set stage.option=value`.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace keel::proto {

// The stages Keel knows, in pipeline order.
const std::vector<std::string>& known_stages();
bool is_known_stage(std::string_view stage);
// Parses "a,b,c" into stage names; fails naming an unknown stage or a repeated one.
std::vector<std::string> parse_stage_list(std::string_view comma_separated);
// Checks a stage list from a document (non-empty, known, no repeats, pipeline order kept).
void validate_stage_list(const std::vector<std::string>& stages, const std::string& path);

// Applies "stage.option=value" to `options`. The value is JSON when it parses as JSON
// (numbers, true/false, arrays), otherwise a string. Fails on a missing '.', '=' or stage.
// "calibration.<sensor>.<key>=<pose JSON>" sets an extrinsic override instead
// (proto/calibration.h), replacing that sensor's earlier one; checked at once.
void apply_option_assignment(nlohmann::json& options, std::string_view assignment);
// Checks that `options` is {"known_stage": {...}, ..., "calibration": {...}} (the overrides'
// form: proto::parse_calibration).
void validate_options(const nlohmann::json& options, const std::string& path);

}  // namespace keel::proto
