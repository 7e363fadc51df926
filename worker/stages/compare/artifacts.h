// What the `compare` stage writes: changes.json and the change maps, one per map and the hull.
#pragma once

#include <string>

namespace keel::pipeline {

inline constexpr const char* kChangesFile = "changes.json";
inline constexpr const char* kHullChangeName = "hull";

// change_<name>.drc / .ply.
inline std::string change_draco_file(const std::string& name) { return "change_" + name + ".drc"; }
inline std::string change_ply_file(const std::string& name) { return "change_" + name + ".ply"; }

}  // namespace keel::pipeline
