// Where the map's world frame is on the earth (issue 30): every JSON file the map stage writes
// (the Draco sidecars) gains `"origin": {latitude_deg, longitude_deg, height_m, frame: "ENU"}`
// when mission.yaml states an `origin`, so a viewer or GIS can place the products on a map.
// Missions without an origin keep their files as they were.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "proto/mission_manifest.h"

namespace keel::pipeline {

// {"latitude_deg", "longitude_deg", "height_m", "frame": "ENU"}.
nlohmann::json origin_json(const proto::GeoOrigin& origin);

// Adds `origin` to each `.json` file among `artifacts` (names in work_dir), rewriting it
// atomically; nothing without an origin. Returns how many files gained it.
size_t add_origin_to_sidecars(const std::filesystem::path& work_dir,
                              const std::vector<std::string>& artifacts,
                              const std::optional<proto::GeoOrigin>& origin);

}  // namespace keel::pipeline
