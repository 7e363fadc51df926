// What a Draco buffer must satisfy before Draco decodes it. Draco's decoders trust the counts
// in the geometry header: the sequential and kd-tree point cloud decoders size every attribute
// at num_points before reading a value, and the edgebreaker mesh decoder sizes its corner
// table at num_faces and the vertex count. fuzz_draco's first run with valid seeds found a
// 400-byte file whose num_points asked for 4.8 GB. The counts are read here the way Draco reads
// them (its header and metadata decoders, then the first fields of the geometry data) and must
// stay within limits the caller can afford.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace keel::io {

// The most points (a mesh's vertices) and faces a Draco file may declare. No bound relative to
// the file's size is sound: Draco's kd-tree coder stores 200,000 copies of one point in 171
// bytes (draco_header_check_test), so the bound is absolute. Keel's largest maps and hulls
// hold about 1e8 points (tests/bench/map_tiles at 100 M); 2^28 points are 3 GiB of float
// positions alone. A caller short of memory (the fuzz harness) passes less.
struct DracoLimits {
  uint64_t max_points = uint64_t{1} << 28;
  uint64_t max_faces = uint64_t{1} << 28;
};

struct DracoDeclaredCounts {
  bool mesh = false;
  uint64_t points = 0;          // points of a cloud, vertices of a mesh
  uint64_t split_vertices = 0;  // edgebreaker: a vertex more for each split symbol, merged later
  uint64_t faces = 0;           // meshes only
};

// The counts the geometry header declares, or nothing when Draco's own decoder would stop
// before reading them (not a Draco file, an unknown version or method, a header cut short):
// the decoder then reports that itself, without allocating.
std::optional<DracoDeclaredCounts> read_draco_counts(const std::string& bytes);

// Throws std::runtime_error naming `what` when the bitstream is not the one Debian's Draco
// (1.5) writes, point clouds 2.3 and meshes 2.2, or the declared points (with split vertices)
// or faces exceed `limits`. Older bitstreams take Draco's backwards-compatibility paths,
// which read further counts of their own (fuzz_draco: a 2.2 kd-tree cloud's attribute data
// declared points again and asked 3.4 GB); Keel's maps and hulls are all 2.3 and 2.2.
void check_draco_header(const std::string& bytes, const std::string& what,
                        const DracoLimits& limits = {});

}  // namespace keel::io
