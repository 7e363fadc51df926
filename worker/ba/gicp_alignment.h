// Localising to the prior model, Sec. 2.5 of seed 001: generalized ICP [54] of the
// SLAM-corrected DVL range returns (world frame) onto the vertices of the CAD mesh. The result
// is the initial guess of x_gM and the mean of its Eq. (8) prior. PCL stays in the .cc (it
// compiles slowly).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "worker/ba/ba_options.h"
#include "core/pose.h"
#include "core/triangle_mesh.h"

namespace keel::ba {

struct GicpAlignment {
  Pose3 T_world_model = Pose3::Identity();
  bool ran = false;  // false: too few returns, the guess is returned
  bool converged = false;
  double fitness = 0;  // PCL's mean squared correspondence distance (m^2)
};

GicpAlignment align_dvl_returns_to_model(const std::vector<Eigen::Vector3d>& dvl_points_world,
                                         const TriangleMesh& cad_mesh,
                                         const Pose3& T_world_model_guess,
                                         const GicpOptions& options);

}  // namespace keel::ba
