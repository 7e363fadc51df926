// Writes a TriangleMesh as a binary PLY, with optional per-vertex scalar fields (e.g. the
// CAD deviation), for viewers without Draco (MeshLab, CloudCompare, ParaView).
#pragma once

#include <filesystem>
#include <vector>

#include "core/triangle_mesh.h"
#include "worker/io/mesh/mesh_scalar_field.h"

namespace keel::io {

struct PlyMeshWriteOptions {
  // float32 positions keep ~0.1 mm at 1 km from the origin; use double for geo-referenced
  // (UTM) coordinates.
  bool double_positions = false;
};

// Writes x/y/z, nx/ny/nz and red/green/blue when the mesh has them, then each field as a
// float property, and faces as `list uchar int vertex_indices`. Throws std::invalid_argument
// for bad fields or indices, std::runtime_error naming the file when writing fails.
void write_ply_mesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                    const std::vector<ScalarField>& vertex_fields = {},
                    const PlyMeshWriteOptions& options = {});

}  // namespace keel::io
