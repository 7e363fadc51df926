// Internal to keel_mesh_io: the summary of a decoded Draco geometry, for draco_codec.cc (which
// has the decoded geometry of its round trip at hand) and draco_summary.cc.
#pragma once

#include <cstddef>

#include "worker/io/draco/draco_summary.h"

namespace draco {
class PointCloud;
}

namespace keel::io {

// `faces`: the mesh's face count; `is_mesh` selects the kind.
DracoSummary summarize_geometry(const draco::PointCloud& geometry, bool is_mesh, size_t faces);

}  // namespace keel::io
