// The factor graph of Sec. 2.6, seed 001 (Fig. 8-9) for one mode of Sec. 4, solved with
// Ceres. Variables: vehicle poses x_gv_i, servo angles theta_v_i_s_i, the servo-to-camera
// extrinsic x_sc_T, the model pose x_gM and the landmarks l_k. Factors:
//   Eq. (8)  full-state priors on x_gM (from GICP, Sigma = I_6), on the first pose (gauge) and
//            on x_sc_T (its calibration);
//   Eq. (9)  depth, pitch, roll per keyframe;          Eq. (10) servo angle per keyframe;
//   Eq. (11) odometry;                                 Eq. (12)/(13) stereo/monocular, Huber;
//   Eq. (14) DVL raycast ranges, Huber;                Eq. (4)-(7) surface constraints
//            (none in `naive`, lambda = 1 in `geva`, max-mixture in `proposed`).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "worker/ba/ba_options.h"
#include "worker/ba/ba_problem.h"
#include "worker/ba/ba_result.h"
#include "worker/ba/dvl_raycast_factor.h"
#include "core/mesh_query.h"

namespace keel::ba {

// The state every mode starts from: initial poses, triangulated landmarks, the GICP x_gM
// (also the mean of its prior) and the DVL beams that passed the gate.
struct BaInitialState {
  std::vector<Pose3> T_world_vehicle;
  std::vector<double> servo_angle_rad;  // measured (Eq. 10's z), also the start
  Pose3 T_servo_camera = Pose3::Identity();
  Pose3 T_world_model = Pose3::Identity();
  std::vector<FeatureTrack> tracks;              // landmarks' observations
  std::vector<Eigen::Vector3d> landmarks_world;  // parallel to tracks
  std::vector<DvlBeam> beams;
  std::vector<int> beam_keyframe;  // parallel to beams
};

// Model-free initialisation (see BaOptions::slam_initialisation): the graph without x_gM, DVL
// raycasts and surface factors, i.e. what the vehicle's online visual SLAM optimises, run from
// `state` and written back into its poses, servo angles, extrinsic and landmarks.
BaInitialisation refine_initial_state(const BaProblem& problem, const MeshQuery& mesh,
                                      BaInitialState& state, const BaOptions& options);

// Builds the graph for `mode` from `problem` (keyframe times, odometry, depth/pitch/roll, rig)
// and `initial`, runs Ceres and reads the result back. `mesh` is the CAD mesh's query.
BaModeResult solve_ba_mode(const BaProblem& problem, const MeshQuery& mesh,
                           const BaInitialState& initial, BaMode mode, const BaOptions& options);

// Measured minus predicted range, and the hit point, of every beam that hits the mesh (Fig. 18).
std::vector<DvlBeamResidual> dvl_range_residuals(const MeshQuery& mesh, const ServoMount& mount,
                                                 const std::vector<DvlBeam>& beams,
                                                 const std::vector<int>& beam_keyframe,
                                                 const std::vector<Pose3>& T_world_vehicle,
                                                 const std::vector<double>& servo_angle_rad,
                                                 const Pose3& T_world_model, double max_range_m);

}  // namespace keel::ba
