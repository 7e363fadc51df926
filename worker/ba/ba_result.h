// Output of model-assisted bundle adjustment: one BaModeResult per mode of Sec. 4, seed 001.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "worker/ba/ba_options.h"
#include "core/pose.h"

namespace keel::ba {

struct BaLandmark {
  int64_t id = 0;  // FeatureTrack::landmark_id (the frontend numbers its tracks 0..n-1)
  Eigen::Vector3d position_world = Eigen::Vector3d::Zero();  // l_i
  // h(x_gM, l_i) of Eq. (5) at the final state: signed distance to the CAD mesh, positive
  // outside (on the side the outward normals point to).
  double signed_distance_m = 0;
  // argmax of Eq. (7) at the final state: 1 = on the nominal model, 0 = foreign structure.
  // In every mode this is the label the max-mixture would assign; `geva` optimised with
  // lambda = 1 throughout and `naive` with no surface factor at all.
  int lambda = 0;
  std::vector<int> keyframes;  // keyframes observing it
  // l_i placed again by its reprojections alone (Eqs. 12-13), with every pose, servo angle,
  // the extrinsic and x_gM held at the solution, and its h. The surface factor pulls a
  // feature whose depth few views constrain towards the model while lambda = 1 (below
  // |h| = 5.6 cm with the paper's sigmas), so the BA's own h reads a low bump lower still;
  // measuring the deviation from the model with features the model pulled in is circular
  // (inspection_point() below). Equal to the above in `naive` (no surface factor).
  Eigen::Vector3d vision_position_world = Eigen::Vector3d::Zero();
  double vision_signed_distance_m = 0;
  // Standard deviation of that position along its least constrained direction (the square
  // root of the largest eigenvalue of (J^T J)^-1 of its reprojections, whitened by
  // pixel_sigma): a bound on the sigma of its h. A feature seen from a short baseline (a lane's
  // end) has centimetres here; infinity when its rays do not fix it.
  double vision_sigma_m = 0;
};

// Where inspect measures a landmark's structural deviation. A feature the max-mixture put on
// the model (lambda = 1) whose own rays place it off the model by more than `sigmas` of their
// uncertainty is structure the surface factor pulled in (Eq. 7 labels everything below
// |h| = 5.6 cm on the model with the paper's sigmas): its ray-only position and h. Any other
// feature: the BA's, which the model prior regularises where the rays do not (a feature at a
// lane's end, seen from a short baseline, can stand centimetres off the hull by noise alone:
// with the ray-only positions for every feature, keel-sim hauv-hull seed 9 and the KCS survey
// each got a false shape). 3 sigmas: a 99.7 % test.
struct InspectionPoint {
  Eigen::Vector3d position_world = Eigen::Vector3d::Zero();
  double signed_distance_m = 0;
};
InspectionPoint inspection_point(const BaLandmark& landmark, double sigmas = 3.0);

// A landmark seen from one keyframe, in that keyframe's top camera frame (the input of
// Algorithm 1, seed 001: f_x, f_y from here, d = |h|).
struct CameraFramePoint {
  size_t landmark = 0;  // index into BaModeResult::landmarks
  Eigen::Vector3d point_camera = Eigen::Vector3d::Zero();
  double signed_distance_m = 0;
  int lambda = 0;
};

// Eq. (14)'s residual of one DVL beam: measured minus predicted range, and where the predicted
// ray meets M_prior, in the model (CAD) frame. Fig. 18(a)-(b) paint these on the hull.
struct DvlBeamResidual {
  int keyframe = 0;
  Eigen::Vector3d hit_model = Eigen::Vector3d::Zero();
  double residual_m = 0;
};

// The residuals alone, in order.
std::vector<double> residual_values(const std::vector<DvlBeamResidual>& beams);

struct BaModeResult {
  BaMode mode = BaMode::kProposed;
  // Ceres iterations, successful and unsuccessful (Ceres counts iteration 0, the initial
  // state, as a successful step).
  int iterations = 0;
  int unsuccessful_steps = 0;  // of those, steps Levenberg-Marquardt rejected
  double solve_time_s = 0;     // wall
  double solve_cpu_s = 0;      // CPU of the whole process during the solve (all threads)
  double initial_cost = 0;     // Ceres cost, 0.5 * sum of squared whitened residuals
  double final_cost = 0;
  bool converged = false;
  std::string termination;  // Ceres' message
  // Fig. 16: fraction of landmarks with lambda = 1, at the initial state (index 0) and after
  // each Ceres iteration. Empty for `naive` (no surface factors to label).
  std::vector<double> lambda1_fraction_per_iteration;
  // Fig. 17: Ceres cost per iteration, iteration 0 being the initial state (a rejected step
  // keeps the cost).
  std::vector<double> cost_per_iteration;
  // Fig. 18: every DVL beam used that hits the mesh, at the start (after GICP) and at the end.
  std::vector<DvlBeamResidual> dvl_residuals_initial;
  std::vector<DvlBeamResidual> dvl_residuals_final;

  std::vector<Pose3> T_world_vehicle;       // per keyframe, x_gv_i
  std::vector<double> servo_angle_rad;      // per keyframe, theta_v_i_s_i
  std::vector<Pose3> T_world_camera;        // per keyframe, top camera
  Pose3 T_world_model = Pose3::Identity();  // x_gM
  // Marginal standard deviation of x_gM's translation along the axes of its own (model) frame
  // at the solution, m, from the Gauss-Newton covariance (Ceres Covariance, sparse QR): along a
  // hull's length it shows how little the survey fixes the model there. Empty when the
  // covariance could not be computed (rank-deficient) or was not asked for.
  std::vector<double> model_translation_sigma_m;
  Pose3 T_servo_camera = Pose3::Identity();  // x_sc_T
  std::vector<BaLandmark> landmarks;
};

struct BaFrontendStats {
  bool ran = false;  // false when the problem carried ready-made tracks
  int keyframe_pairs_matched = 0;
  int keyframe_pairs_verified = 0;
  int verified_matches = 0;
  int tracks = 0;
};

struct BaInitialisation {
  bool ran = false;
  int iterations = 0;
  double solve_time_s = 0;
  double initial_cost = 0;
  double final_cost = 0;
};

struct BaResult {
  BaFrontendStats frontend;
  BaInitialisation initialisation;  // BaOptions::slam_initialisation
  int tracks_in = 0;                // tracks handed to triangulation
  int landmarks_triangulated = 0;   // tracks kept as landmarks
  // Dropped after the SLAM initialisation: out of the triangulation's depth or reprojection gate,
  // or a monocular landmark left with fewer than TriangulationOptions::min_monocular_views views.
  int landmarks_dropped_after_initialisation = 0;
  // Observations removed by the post-initialisation reprojection gate, and that gate in pixels
  // (TriangulationOptions::post_initialisation_gate_sigmas; 0: not run).
  int observations_dropped_after_initialisation = 0;
  double post_initialisation_gate_px = 0;
  int dvl_ranges_in = 0;
  int dvl_ranges_used = 0;  // after the gate of BaOptions::dvl_gate_m
  bool gicp_ran = false;
  bool gicp_converged = false;
  double gicp_fitness = 0;  // PCL's mean squared correspondence distance (m^2)
  Pose3 T_world_model_initial = Pose3::Identity();  // x_gM prior (GICP or the guess)
  std::vector<BaModeResult> modes;                  // in BaOptions::modes order

  const BaModeResult* find(BaMode mode) const;
};

// Landmarks observed from keyframe `keyframe`, in its top camera frame.
std::vector<CameraFramePoint> landmarks_in_camera(const BaModeResult& result, int keyframe);

}  // namespace keel::ba
