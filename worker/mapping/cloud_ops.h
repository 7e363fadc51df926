// Small operations on keel::PointCloud that keep every per-point field in step with xyz.
#pragma once

#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"

namespace keel::mapping {

// Keeps point k iff keep[k] != 0, preserving order; returns the number removed.
size_t keep_points(PointCloud& cloud, const std::vector<uint8_t>& keep);
// Removes points with a non-finite coordinate (organized lidar clouds mark misses with NaN).
size_t remove_non_finite(PointCloud& cloud);
// p <- T * p for every point (in double, stored as float).
void transform_points(PointCloud& cloud, const Pose3& T);
// Appends `src` to `dst`. A field is kept only if both clouds carry it (an empty `dst` takes
// the fields of `src`).
void append_points(PointCloud& dst, const PointCloud& src);
// Throws std::invalid_argument when a per-point field has a size other than xyz.size().
void check_field_sizes(const PointCloud& cloud, const char* what);

}  // namespace keel::mapping
