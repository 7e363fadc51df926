// Model-assisted bundle adjustment against a CAD mesh: seed 001 (Ozog et al. 2017), Sec. 2
// and the three methods of Sec. 4. The whole pipeline, as numbered steps:
//   1. validate the problem (ba_problem.h: clear errors naming the field);
//   2. feature tracks: problem.tracks, or the SIFT frontend on the keyframe images (Sec. 2.7);
//   3. initial landmarks: triangulation from the initial poses, measured servo angles and the
//      calibrated extrinsic (triangulation.h);
//   4. SLAM initialisation (BaOptions::slam_initialisation): the model-free graph, as the
//      vehicle's online SLAM would solve it, so the modes start from a SLAM-quality state;
//      then landmarks that no longer pass the triangulation gates (depth range, reprojection;
//      wrong matches) are dropped;
//   5. x_gM: GICP of the DVL returns (world, from the SLAM-corrected poses) onto the CAD
//      vertices (Sec. 2.5); it is the start and the Eq. (8) prior of x_gM;
//   6. DVL beams whose predicted range misses the mesh or is off by more than
//      BaOptions::dvl_gate_m are left out (foreign objects, beams past the CAD's edge);
//   7. for each of BaOptions::modes: the factor graph of Sec. 2.6 (ba_graph.h), solved by
//      Ceres from the same initial state.
// No I/O. Thread use: BaOptions::num_threads for Ceres and batch mesh queries.
//
// Usage:
//   keel::ba::BaProblem problem;           // keyframes, odometry, tracks or images, DVL, mesh
//   keel::ba::BaOptions options;           // paper defaults; options.modes picks the methods
//   keel::ba::BaResult result = keel::ba::run_model_assisted_ba(problem, options);
//   const auto* proposed = result.find(keel::ba::BaMode::kProposed);
//   for (auto& p : keel::ba::landmarks_in_camera(*proposed, keyframe)) ...  // Algorithm 1 input
#pragma once

#include "worker/ba/ba_options.h"
#include "worker/ba/ba_problem.h"
#include "worker/ba/ba_result.h"

namespace keel::ba {

// Throws std::invalid_argument for invalid input (naming the field) or when no landmark
// survives triangulation.
BaResult run_model_assisted_ba(const BaProblem& problem, const BaOptions& options = {});

}  // namespace keel::ba
