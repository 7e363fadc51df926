// Synthetic inputs for model-assisted visual mapping (seed 001, section 3): a flat hull patch
// (the CAD prior, plane z = 0, outward normal +z), cylinder-like objects on it (flat discs of
// known height, like the 0.11 m cylinder of section 4.2.1), bundle-adjusted features with their
// exact deviation h, and downward-looking cameras. Used by the tests and bench_inspect.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "core/pose.h"
#include "core/triangle_mesh.h"
#include "worker/inspect/inspect_input.h"

namespace keel::inspect::testing {

struct Bump {
  Eigen::Vector2d center_xy = Eigen::Vector2d::Zero();
  double radius_m = 0.3;
  double height_m = 0.11;  // negative: a dent
  int num_landmarks = 60;  // uniform over the top disc
};

struct SceneOptions {
  int nx = 81;  // CAD grid vertices along x and y, centred on the origin
  int ny = 81;
  double spacing_m = 0.05;
  std::vector<Eigen::Vector2d> camera_xy;  // cameras at (x, y, standoff) looking down (-z)
  double standoff_m = 1.5;
  double half_footprint_m = 1.0;  // a camera sees features with |dx|, |dy| <= this
  int num_hull_landmarks = 400;   // on the plane, outside the bumps
  double hull_noise_m = 0.005;    // Gaussian, clipped at 3 sigma
  double bump_noise_m = 0.003;
  std::vector<Bump> bumps;
  uint32_t seed = 1;
};

// A regular grid in the plane z = 0, two triangles per cell, counter-clockwise seen from +z.
TriangleMesh make_flat_patch(int nx, int ny, double spacing_m);

// Camera at (x, y, standoff_m) with its optical axis (+z) along world -z.
Pose3 camera_looking_down(const Eigen::Vector2d& xy, double standoff_m);

// The CAD patch, the cameras and the features (h = the feature's z: the plane is the prior).
InspectInput make_scene(const SceneOptions& options);

}  // namespace keel::inspect::testing
