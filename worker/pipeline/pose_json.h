// A pose in Keel's JSON artifacts ({"translation": [x, y, z], "rotation_xyzw": [x, y, z, w]}),
// and arrays of numbers read strictly: ba_solution.json, trajectories.json, sidecars.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/pose.h"

namespace keel::pipeline {

nlohmann::json pose_to_json(const Pose3& T);
// Throws proto::ContractError naming `path` and the field.
Pose3 pose_from_json(const nlohmann::json& value, const std::string& path);

// `size` finite numbers (any count when 0) at `path`; throws proto::ContractError naming it.
template <typename T>
std::vector<T> json_numbers(const nlohmann::json& value, const std::string& path, size_t size);

}  // namespace keel::pipeline
