// Writes a point cloud as a binary PLY with optional per-point scalar fields (`deviation`,
// `density`, ...), for tools without Draco.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/mesh/mesh_scalar_field.h"

namespace keel::io {

// Writes float x/y/z, then `intensity` (float), `ring` (ushort) and `time` (float, s after
// cloud.t_ns) when the cloud has them, then each field as a float property. Throws
// std::invalid_argument for fields of the wrong size or name, std::runtime_error naming the
// file when writing fails.
void write_ply_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                     const std::vector<ScalarField>& point_fields = {});
// The concatenation of `parts` (a combined map's sensor maps) without building it: the same
// bytes as write_ply_cloud of the cloud mapping::append_points would merge (intensity, ring and
// time written when every non-empty part has them).
void write_ply_cloud(const std::filesystem::path& path,
                     const std::vector<const PointCloud*>& parts);

// The header write_ply_cloud writes for `points` points with those properties, for writers
// that stream a cloud in parts.
std::string ply_cloud_header(uint64_t points, bool intensity, bool ring, bool time,
                             const std::vector<std::string>& fields = {});

}  // namespace keel::io
