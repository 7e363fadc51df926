// Algorithm 1 of seed 001 (section 3.2): detect shapes at one camera pose by clustering the
// visible features that deviate from the CAD prior and meshing each cluster as a 2.5D alpha
// shape in that camera's frame.
#pragma once

#include <vector>

#include "core/pose.h"
#include "worker/inspect/alpha_shape_25d.h"
#include "worker/inspect/inspect_input.h"
#include "worker/inspect/inspect_options.h"

namespace keel::inspect {

struct DetectedShape {
  int view = -1;  // index into InspectInput::T_world_camera
  // The 2.5D shape M_S in the camera frame; shape.source_index indexes `landmarks` below.
  Shape25d shape;
  // Every feature of the DBSCAN cluster (indices into InspectInput::landmarks), ascending;
  // a superset of the shape's vertices (duplicates in (x, y) and points left outside every
  // alpha triangle belong to the cluster too).
  std::vector<int> landmarks;
};

// Algorithm 1 for camera `view` at T_world_camera, given the indices of the features visible
// in it (is_visible(), line 3 of Algorithm 2). Features behind the camera (f_z <= 0) cannot
// have been seen and are skipped. Clusters whose alpha shape has no triangle are dropped:
// they give Algorithm 2 nothing to intersect.
std::vector<DetectedShape> detect_shapes(int view, const Pose3& T_world_camera,
                                         const std::vector<Landmark>& landmarks,
                                         const std::vector<int>& visible,
                                         const InspectOptions& options);

}  // namespace keel::inspect
