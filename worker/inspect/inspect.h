// Model-assisted visual mapping, seed 001 section 3: Algorithm 1 (shape detection) at every
// camera pose, fused into the CAD prior by Algorithm 2 (remeshing, Eq. 15), and the shapes
// merged into objects for shapes.json. A plain library: no I/O.
#pragma once

#include <vector>

#include "core/triangle_mesh.h"
#include "worker/inspect/deviation_threshold.h"
#include "worker/inspect/inspect_input.h"
#include "worker/inspect/inspect_options.h"
#include "worker/inspect/shape_detection.h"
#include "worker/inspect/shape_report.h"

namespace keel::inspect {

struct InspectStats {
  int num_views = 0;
  int num_views_with_shapes = 0;
  int num_detections = 0;       // per-view shapes from Algorithm 1
  int num_shapes_rejected = 0;  // merged shapes seen in fewer than min_shape_views views
  int num_updates = 0;          // evaluations of line 11 of Algorithm 2 (Eq. 15)
  int num_vertices_moved = 0;   // vertices with n > 0
  double detect_s = 0.0;        // wall time of Algorithm 1 over all views
  double fuse_s = 0.0;          // wall time of Algorithm 2 (without detection)
  double deviation_s = 0.0;     // wall time of the per-vertex deviations
};

struct InspectResult {
  // M_new: the prior's faces, vertices moved by Eq. (15); the stage writes mesh_remeshed.drc.
  TriangleMesh remeshed;
  // Per vertex of `remeshed`: the signed distance of the remeshed vertex to M_prior (Eq. 5,
  // positive outside), i.e. how far the fused structure stands off the CAD surface there; 0 for
  // vertices no ray moved. We report this rather than the length of the move because a vertex
  // moves along a slanted camera ray, and that length overstates the height of the structure.
  std::vector<double> vertex_deviation_m;
  std::vector<int> vertex_update_count;  // n of Eq. (15)
  // The per-view shapes of Algorithm 1 that belong to a kept shape (the ones fused).
  std::vector<DetectedShape> detections;
  std::vector<ShapeSummary> shapes;  // merged objects seen in >= min_shape_views views

  DeviationThreshold threshold;  // the tau line 6 of Algorithm 1 used
  InspectStats stats;
};

// Runs Algorithm 2 over input.T_world_camera in order, calling Algorithm 1 at each pose with
// the features whose `views` list it. Throws std::invalid_argument for bad input or options,
// naming the field.
InspectResult run_inspect(const InspectInput& input, const InspectOptions& options = {});

// Throws std::invalid_argument naming the option and the range expected.
void validate(const InspectOptions& options);

}  // namespace keel::inspect
