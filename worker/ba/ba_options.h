// Options of model-assisted bundle adjustment, with the defaults of seed 001 (Ozog et al.
// 2017) where the paper gives them; where it does not, the choice is written next to it.
#pragma once

#include <string>
#include <vector>

namespace keel::ba {

// The three methods compared in Sec. 4 of seed 001.
enum class BaMode {
  kNaive,     // no surface factors (lambda_i = 0, "all surface constraints disabled")
  kGeva,      // every feature on the model: lambda_i = 1 (Geva et al. [26])
  kProposed,  // binary Gaussian max-mixture, lambda_i from Eq. (7)
};
const char* to_string(BaMode mode);
BaMode ba_mode_from_string(const std::string& name);  // "naive" | "geva" | "proposed"

constexpr double kDegToRad = 0.017453292519943295;

// The normal that linearises a DVL beam's range (dvl_raycast_factor.h).
enum class DvlRangeNormal { kInterpolated, kFacet };

// Sec. 2.7 frontend. The paper gives only its structure (SIFT, nearest-neighbour matching,
// RANSAC with an essential matrix scored by Sampson distance, or rigid alignment of
// triangulated stereo points); the numbers are ours.
struct FrontendOptions {
  int max_features = 2000;              // SIFT features per image (strongest kept)
  double ratio_test = 0.8;              // Lowe's ratio between the best and second-best match
  int match_window = 2;                 // match keyframe i with i+1 .. i+match_window
  double essential_threshold_px = 1.0;  // RANSAC Sampson distance threshold (monocular)
  double ransac_confidence = 0.999;
  int min_inliers = 15;  // a keyframe pair with fewer verified matches is dropped
  // Stereo: a top-bottom match must reproject onto both detections (rectified pair).
  double stereo_max_reprojection_px = 2.0;
  // Stereo: RANSAC rigid alignment of triangulated points between keyframes.
  double rigid_inlier_threshold_m = 0.05;
  int rigid_ransac_iterations = 500;
  // Monocular: an essential-matrix inlier must also triangulate (E's pose, the initial poses'
  // baseline) in front of both cameras between these depths; the epipolar test alone accepts
  // any match near infinity (feature_frontend.cc). Same range as TriangulationOptions.
  bool gate_two_view_depth = true;
  double min_depth_m = 0.1;
  double max_depth_m = 20.0;
};

// Sec. 2.5: GICP of SLAM-corrected DVL returns onto the CAD vertices.
struct GicpOptions {
  bool enabled = true;
  double max_correspondence_distance_m = 1.0;
  int max_iterations = 100;
  int min_points = 20;  // fewer DVL returns: keep T_world_model_guess
};

// Landmark initialisation from the initial poses (not in the paper, which starts from its
// online SLAM's landmarks).
struct TriangulationOptions {
  double max_reprojection_px = 20.0;  // initial poses drift; the BA does the rest
  double min_parallax_deg = 1.0;      // monocular tracks seen from too close to one ray
  double min_depth_m = 0.1;
  double max_depth_m = 20.0;
  // After the model-free initialisation the poses agree with the images, so an observation
  // reprojecting further than this many pixel sigmas is a wrong match: it leaves its track
  // (triangulation.h, gate_landmark_observations). 3.72 sigma is the 99.9 % quantile of a 2-D
  // Gaussian error's norm (chi-square, 2 dof). The Huber loss alone only bounds such a match's
  // pull; on a landmark seen twice it still decides where the landmark sits, and inspect reads
  // heights off landmarks.
  double post_initialisation_gate_sigmas = 3.72;
  // The gate's sigma: Eq. (12)-(13)'s pixel_sigma (2 px), or, when true, the smaller of it and
  // the noise measured on the initialised landmarks (robust_pixel_sigma_px, dof-corrected
  // median). The paper's 2 px is a modelling figure; where the images are sharper a 7.4 px gate
  // keeps matches several px off along the epipolar line.
  bool measure_pixel_sigma = true;
  // Floor of that measured sigma. SIFT localises a keypoint to ~0.1 px at best; below that the
  // median measures numerical noise (exact or synthetic tracks), and a gate of a few 1e-7 px
  // would drop good landmarks.
  double min_pixel_sigma_px = 0.1;
  // Views a monocular track must keep after that gate. Two views have no redundancy along the
  // epipolar line: a wrong match displaced along it fits both rays exactly and only its depth
  // is wrong, so no reprojection gate can see it. On keel-sim hauv-hull (120 s) such two-view
  // tracks on the cylinder's top, 5-11 deg apart, put it at 0.149 / 0.147 / 0.121 m on seeds
  // 1-3 (true 0.110 m; 0.113 / 0.115 / 0.116 m with 3 views). A parallax gate does not help (their
  // parallax is ample), nor does comparing depth to the DVL-ranged hull (a foreign object stands
  // off the hull by design). A third view checks the depth: the wrong match must then also land on
  // a second epipolar line. The paper (Sec. 4.2) lets such outliers through and relies on DBSCAN's
  // 3-point minimum; inspect takes a shape's height from its highest landmark, so one outlier
  // inside a cluster counts.
  int min_monocular_views = 3;
};

struct BaOptions {
  std::vector<BaMode> modes = {BaMode::kNaive, BaMode::kGeva, BaMode::kProposed};

  // Eq. (4): sigma_1 for features on the model, sigma_0 for features off it.
  double sigma0_m = 1.0;
  double sigma1_m = 0.02;
  double surface_offset_m = 0.0;  // z_s_i; 0 in the paper's experiments

  // Eq. (8): prior on x_gM from GICP with Sigma = I_6 (1 m, 1 rad).
  double model_prior_sigma_m = 1.0;
  double model_prior_sigma_rad = 1.0;
  // Eq. (8) on the first vehicle pose: fixes the gauge of the world frame (x, y, yaw are
  // otherwise free up to x_gM's loose prior). Not numbered in the paper; tight on purpose.
  double first_pose_prior_sigma_m = 0.01;
  double first_pose_prior_sigma_rad = 0.1 * kDegToRad;
  // Eq. (8) on the servo-to-camera extrinsic x_sc_T ("not precisely calibrated"); the paper
  // gives no figure, we allow 5 cm and 2 degrees around the calibration.
  double extrinsic_prior_sigma_m = 0.05;
  double extrinsic_prior_sigma_rad = 2.0 * kDegToRad;

  // Eq. (9): depth, pitch, roll.
  double depth_sigma_m = 0.1;
  double pitch_sigma_rad = 0.1 * kDegToRad;
  double roll_sigma_rad = 0.1 * kDegToRad;

  // Eq. (10): servo angle.
  double servo_sigma_rad = 5.0 * kDegToRad;

  // Eq. (11): odometry sigmas proportional to the keyframes' time difference.
  double odometry_sigma_m_per_s = 0.005;
  double odometry_sigma_rad_per_s = 80.0 * kDegToRad / 3600.0;
  double odometry_min_sigma_m = 1e-4;  // floor for near-simultaneous keyframes
  double odometry_min_sigma_rad = 1e-5;

  // Eq. (12)-(13): reprojection, sigma_c = 2 px, with a Huber M-estimator (Sec. 2.6.5).
  double pixel_sigma = 2.0;
  // Huber thresholds are in sigmas of the whitened residual; 1.345 gives 95 % efficiency
  // under Gaussian noise (the paper names Huber [31] without a threshold).
  double reprojection_huber = 1.345;

  // Eq. (14): DVL ranges, sigma = 3 mm, Huber.
  double dvl_sigma_m = 0.003;
  double dvl_huber = 1.345;
  // Beams whose initial predicted range misses the mesh or is further than this from the
  // measurement are left out (returns from foreign objects, Sec. 2.5, or off-model beams).
  double dvl_gate_m = 0.5;
  double dvl_max_range_m = 30.0;
  // Which normal linearises a beam's range (dvl_raycast_factor.h): the smooth surface's
  // (interpolated) or the hit facet's.
  DvlRangeNormal dvl_range_normal = DvlRangeNormal::kInterpolated;

  // Ceres. SPARSE_SCHUR (landmarks eliminated first, SuiteSparse Cholesky on the reduced
  // camera system) is the paper's "sparse Cholesky" and the fastest at 1,000 keyframes.
  std::string linear_solver = "sparse_schur";  // | "iterative_schur" | "dense_schur"
  int max_iterations = 100;
  // Threads of the mesh queries and of x_gM's covariance; Ceres solves on one thread
  // (ba_graph.cc: its multithreaded sums follow the threads' timing, not a fixed order).
  int num_threads = 2;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;

  // Sec. 2.2 step 1, "Initialize X": the paper starts from its online SLAM's estimate. From
  // raw tracks, measured servo angles (with slop) and a calibration guess, triangulated
  // landmarks are several cm off (mono), enough to put foreign structure inside the 5.6 cm
  // lambda = 1 basin before the first iteration. So we first optimise the model-free graph the
  // online SLAM would (Eq. 8-13: poses, servo angles, extrinsic, landmarks; no x_gM, DVL
  // raycasts or surface factors), then run GICP (Sec. 2.5) from those SLAM-corrected poses,
  // and start every mode from that same state.
  bool slam_initialisation = true;
  int initialisation_max_iterations = 50;

  FrontendOptions frontend;
  GicpOptions gicp;
  TriangulationOptions triangulation;
};

// Throws std::invalid_argument naming the option (e.g. "ba options: sigma1_m") unless every
// sigma, tolerance and count is positive and finite and the modes are not empty.
void validate(const BaOptions& options);

}  // namespace keel::ba
