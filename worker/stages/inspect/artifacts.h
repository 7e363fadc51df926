// What the `inspect` stage writes that other stages read: the remeshed hull and the shapes list
// (`compare` matches shapes and deviations between two hull surveys).
#pragma once

#include <string>

namespace keel::pipeline {

inline constexpr const char* kRemeshedDracoFile = "mesh_remeshed.drc";
inline constexpr const char* kRemeshedPlyFile = "mesh_remeshed.ply";
inline constexpr const char* kShapesFile = "shapes.json";

}  // namespace keel::pipeline
