// YAML -> JSON, so that YAML documents (mission.yaml, truth.yaml) are read by the strict JSON
// contracts of proto/. Plain scalars become null/bool/integer/number when they read as such
// (YAML 1.2 core schema); quoted scalars stay strings. yaml-cpp stays out of this header.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace keel::io {

// `source_name` prefixes errors: "<source>:<line>:<column>: <yaml error>". Duplicate keys
// in a mapping are errors too.
nlohmann::json yaml_to_json(const std::string& yaml_text, const std::string& source_name);
nlohmann::json load_yaml_file(const std::filesystem::path& path);

}  // namespace keel::io
