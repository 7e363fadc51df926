// What the `map` stage writes that other stages read: the maps' file names (`compare` reads
// both jobs' maps; the viewer lists them the same way, docs/artifacts.md).
#pragma once

#include <string>

namespace keel::pipeline {

inline constexpr const char* kCombinedMapName = "combined";

// `map_<sensor>.drc` / `map_<sensor>.ply` (sensor "combined" for the union).
inline std::string map_draco_file(const std::string& sensor) { return "map_" + sensor + ".drc"; }
inline std::string map_ply_file(const std::string& sensor) { return "map_" + sensor + ".ply"; }
// `tiles_<sensor>.tar`: the map's level-of-detail tileset (docs/artifacts.md).
inline std::string map_tiles_file(const std::string& sensor) { return "tiles_" + sensor + ".tar"; }

}  // namespace keel::pipeline
