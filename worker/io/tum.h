// TUM trajectories: one pose per line, `t x y z qx qy qz qw` (T_world_body at t, seconds and
// metres), the format evo reads. '#' starts a comment line.
#pragma once

#include <filesystem>

#include "core/pose.h"

namespace keel::io {

// Fails naming file and line on a wrong field count, a non-number, NaN/inf, |q| off 1 by
// more than 1e-3 (quaternions are normalised otherwise) or a duplicate/decreasing stamp.
Trajectory read_tum(const std::filesystem::path& path);
// Writes 9-digit seconds and shortest round-trip numbers; a '#' header line first.
void write_tum(const std::filesystem::path& path, const Trajectory& trajectory);

}  // namespace keel::io
