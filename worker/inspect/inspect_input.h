// What model-assisted visual mapping needs from bundle adjustment (seed 001, sections 2-3):
// the CAD prior already moved into the world frame by x_gM, the bundle-adjusted features with
// their structural deviation h (Eq. 5), and the camera poses that observed them.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/pose.h"
#include "core/triangle_mesh.h"

namespace keel::inspect {

struct Landmark {
  Eigen::Vector3d point_world = Eigen::Vector3d::Zero();  // l_i after BA
  // h(x_gM, l_i) of Eq. (5): signed distance to M_prior, positive outside (towards the water).
  double h_m = 0.0;
  // lambda of Eq. (7) at the BA's solution: 1 when the max-mixture put the feature on the model.
  // The noise of h is measured over these (deviation_threshold.h).
  int lambda = 0;
  // Indices into InspectInput::T_world_camera of the keyframes that observed this feature;
  // distinct. They serve as is_visible() of Algorithm 2 (line 3): a feature matched in an image
  // lies in that camera's frustum and was not occluded. The paper's is_visible() is every
  // feature in the frustum; tried on keel-sim hauv-hull (seeds 1-3, full survey), it clustered
  // features no image matched together and gave a shape on clean hull (seed 1) and the 0.11 m
  // cylinder 0.129 m high (seed 2), against none and 0.115 m with the views that matched.
  std::vector<int> views;
};

struct InspectInput {
  TriangleMesh cad_in_world;  // M_prior, outward-oriented, in the world (global) frame
  std::vector<Landmark> landmarks;
  // Camera c_T poses: the camera looks along its +z axis (x right, y down, as OpenCV).
  std::vector<Pose3> T_world_camera;
};

// Throws std::invalid_argument naming the field and what was expected (non-finite values,
// out-of-range or repeated view indices, bad face indices, non-rigid poses, empty mesh).
void validate(const InspectInput& input);

}  // namespace keel::inspect
