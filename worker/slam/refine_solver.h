// The `refine` stage's batch solver: a factor graph over keyframes that tightly couples DVL/IMU
// preintegration with recorded odometry, seed 000 Sec. III-IV (Fig. 1(b), Eq. (3) extended by
// D_ij and b^v), solved with Ceres. A pure function of in-memory inputs; no I/O.
//
// Graph (per consecutive keyframes i, j):
//   - prior r_0 on the first keyframe's pose, velocity and biases;
//   - odometry L_ij: relative pose from the recorded odometry (relative_poses_from_trajectory)
//     or from GICP scan matching (gicp_odometry.h) when a mission has none;
//   - IMU preintegration I_ij ([27]) and bias random walks for b^w, b^a (Eq. (6)-(7));
//   - DVL preintegration D_ij (Eq. (11)-(16), Algorithm 1) and the b^v random walk;
//   - loop closures L_pq between non-consecutive keyframes (Cauchy-robustified);
//   - beyond the paper (Sec. VII): the DVL scale factor s_d and the DVL-IMU extrinsic rotation
//     as states with weak priors; DVL dropouts leave the intervals they touch without a D_ij.
// Degeneracy (Sec. IV-B): an odometry edge whose information has a small eigenvalue marks its
// keyframe degenerate; its odometry factor is dropped so the keyframe relies on the IMU and DVL
// factors, and that keyframe's biases are set to zero and held (they are unobservable then).
// Where D_ij exists, I_ij's position residual is given zero weight (Sec. IV-B), except, beyond
// the paper, over degenerate intervals (RefineOptions::imu_position_when_degenerate), where it
// is kept and the biases, observable through it, are estimated rather than zeroed.
//
// Frames: inputs and outputs use the body frame of the mission (T_world_body, world z up,
// gravity -z). Internally states live in the IMU frame B, as in the paper.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/slam/degeneracy.h"
#include "worker/slam/dvl_imu_reconciliation.h"
#include "worker/slam/dvl_preintegration.h"
#include "worker/slam/gnss_factor.h"
#include "worker/slam/imu_preintegration.h"
#include "worker/slam/map_pose_noise.h"
#include "worker/slam/relative_pose.h"
#include "worker/slam/sensor_samples.h"

namespace keel::slam {

enum class DegeneracyHandling {
  kDropFactor,           // seed 000: rely on IMU and DVL factors (default)
  kKeepWellConditioned,  // keep the odometry's well-observed directions only
  kIgnore,               // flag, but keep the factor as it is
};

// Which marginal covariances to compute after the solve (Ceres covariance, SPARSE_QR).
enum class CovarianceScope {
  kNone,
  kCalibration,  // s_d and the DVL-IMU extrinsic rotation only (~0.3 s, 10-minute mission)
  kAll,          // also every keyframe's pose and biases: ~10x the solve time, since
                 // SPARSE_QR recovers one column of the inverse per tangent dimension
};

struct RefineOptions {
  // Sensor models (seed 000 Table I).
  ImuNoise imu_noise;
  DvlNoise dvl_noise;
  ReconcileOptions reconcile;  // Algorithm 1 and its gap rule
  double gravity_mps2 = 9.81;
  // An interval with an IMU gap longer than this gets no IMU factor (and no DVL factor,
  // which needs the gyro).
  double max_imu_gap_s = 0.1;

  // Which factors enter the graph.
  bool use_imu = true;
  bool use_dvl = true;
  bool use_odometry = true;
  bool use_loop_closures = true;
  bool drop_imu_position_residual_with_dvl = true;  // Sec. IV-B
  // Beyond the paper: where the odometry is degenerate, I_ij keeps its position residual next to
  // D_ij, so positions rest on the IMU and the DVL together ("rely on IMU and DVL factors").
  // The accelerometer is absolute while the DVL displacement scales with 1/s_d, so along a
  // degenerate axis (where nothing else measures distance) this is what observes s_d; it also
  // ties the velocity states, hence b^a, to the DVL, so the biases stay observable there and
  // are not zeroed. false: the paper's rule everywhere.
  bool imu_position_when_degenerate = true;

  // Degeneracy (Sec. IV-B).
  DegeneracyOptions degeneracy;
  DegeneracyHandling degeneracy_handling = DegeneracyHandling::kDropFactor;
  bool zero_biases_when_degenerate = true;

  // Beyond the paper (Sec. VII). With estimate_* = false the value is held at its initial
  // value (the paper's Sec. V assumptions 1 and 2).
  bool estimate_dvl_scale = true;
  double dvl_scale_initial = 1.0;
  double dvl_scale_prior_sigma = 0.1;
  bool estimate_dvl_rotation = true;
  double dvl_rotation_prior_sigma_rad = 0.05;

  // Prior r_0 on the first keyframe (Eq. (3)).
  double prior_sigma_position_m = 1e-3;
  double prior_sigma_rotation_rad = 1e-3;
  double prior_sigma_velocity_mps = 0.5;
  double prior_sigma_gyro_bias_radps = 1e-2;
  double prior_sigma_accel_bias_mps2 = 0.1;
  // b^v_0: the DVL's stated accuracy, +-0.1 % of speed (Water Linked A50, seed 000 Sec. V), i.e.
  // ~1 mm/s at USV speeds (0.5-1 m/s). Looser, a constant b^v is free to take up what other
  // factors cannot pin: a lateral b^v trades with an extrinsic yaw error times the forward speed
  // (at 0.05 m/s the yaw estimate wanders by ~3x), and an along-track b^v with the MAP anchors'
  // drift along a degenerate corridor (at 5 mm/s it followed the MAP's walk: a 0.66 % ramp on
  // keel-sim usv-corridor seed 20, issue 19).
  double prior_sigma_dvl_bias_mps = 0.001;

  // MAP anchors (beyond the paper): offline, the online SLAM's global constraints (scan-to-map
  // matching, its loop closures) survive only in its keyframe poses, which are also the initial
  // values (RefineInput::keyframes). Every keyframe is anchored to its recorded pose
  // (MapAnchorFactor): white noise plus a drift state that random-walks along the path
  // travelled in degeneracy (map_pose_noise.h), Huber-robustified. The first keyframe's anchor
  // (drift zero) replaces r_0's pose prior: the anchors together fix the gauge. With
  // estimate_map_noise the noise is re-estimated from the MAP poses' disagreement with the
  // refinement after every pass but the last (so relinearization_passes >= 2 is needed for an
  // estimate); `map_noise` is the first pass's (or the fixed) noise. Anchors observe every
  // keyframe's position, so biases stay observable in degeneracy and are estimated rather than
  // zeroed.
  bool use_map_anchors = false;
  MapPoseNoise map_noise = MapPoseNoise::isotropic(0.05, 0.01, 0.0);
  bool estimate_map_noise = true;
  MapNoiseEstimateOptions map_noise_estimate;
  double map_anchor_huber_scale = 1.345;  // whitened units; <= 0: plain least squares

  // Loop closures: Cauchy loss scale in whitened units (<= 0: plain least squares), and how
  // far a loop's stamps may be from a keyframe stamp.
  double loop_closure_cauchy_scale = 1.0;
  double measurement_time_tolerance_s = 0.05;

  // GNSS position factors (gnss_factor.h), when RefineInput::gnss has fixes. With at least
  // `min_gnss_fixes_for_gauge` fixes placed they fix the gauge: r_0 keeps no pose part.
  GnssOptions gnss;
  int min_gnss_fixes_for_gauge = 3;

  // Solver.
  int max_iterations = 50;
  // Threads of the covariance's columns; the solve runs on one thread (refine_solver.cc).
  int num_threads = 2;
  // Solve, re-preintegrate at the new biases / s_d / extrinsic, solve again: keeps the
  // first-order corrections of Eq. (27) and [27] Eq. (44) small.
  int relinearization_passes = 2;
  CovarianceScope covariances = CovarianceScope::kCalibration;
};

struct RefineInput {
  Trajectory keyframes;  // keyframe stamps and initial T_world_body (e.g. the online map poses)
  std::vector<ImuSample> imu;  // in the IMU frame
  std::vector<DvlSample> dvl;  // in the DVL frame; empty: no DVL factors
  Pose3 T_body_imu = Pose3::Identity();
  Pose3 T_body_dvl = Pose3::Identity();
  // Body-frame relative poses; stamps must match keyframe stamps within the tolerance.
  std::vector<RelativePoseMeasurement> odometry;       // usually consecutive keyframes
  std::vector<RelativePoseMeasurement> loop_closures;  // non-consecutive keyframes
  // GNSS fixes of the antenna in the world frame (the mission's ENU), in time order.
  std::vector<GnssFix> gnss;
  Pose3 T_body_gnss = Pose3::Identity();  // the antenna's lever arm (its translation)
};

struct KeyframeEstimate {
  TimeNs t_ns = 0;
  Pose3 T_world_body = Pose3::Identity();
  // Tangent [delta p (world, m), delta phi (body, rad)], T = (p + dp, R Exp(dphi)).
  Matrix6d pose_covariance = Matrix6d::Zero();
  Eigen::Vector3d velocity_imu_world_mps = Eigen::Vector3d::Zero();  // of the IMU origin
  Eigen::Vector3d bias_gyro_radps = Eigen::Vector3d::Zero();         // b^w, IMU frame
  Eigen::Vector3d bias_accel_mps2 = Eigen::Vector3d::Zero();         // b^a, IMU frame
  Eigen::Vector3d bias_dvl_mps = Eigen::Vector3d::Zero();            // b^v, IMU frame (Eq. (11))
  Eigen::Matrix3d bias_gyro_covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d bias_accel_covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d bias_dvl_covariance = Eigen::Matrix3d::Zero();
  bool degenerate = false;  // its incoming odometry edge was degenerate
  // MAP path travelled over degenerate keyframes up to this one, m: what the MAP's drift grows
  // with (map_pose_noise.h); its stated position covariance is
  // RefineResult::map_noise.position_covariance(map_drift_path_m).
  double map_drift_path_m = 0.0;
  bool biases_zeroed = false;
  bool imu_position_with_dvl = false;  // I_ij kept its position residual next to D_ij
  // Factors over the interval from the previous keyframe to this one.
  bool has_odometry_factor = false;
  bool has_imu_factor = false;
  bool has_dvl_factor = false;
  DegeneracyReport odometry_degeneracy;  // of the incoming odometry edge, if any
};

struct RefineSummary {
  int iterations = 0;  // over all passes
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double solve_time_s = 0.0;       // Ceres solves
  double covariance_time_s = 0.0;  // Ceres covariance
  double total_time_s = 0.0;
  bool converged = false;
  std::string ceres_report;  // BriefReport of the last pass
  int num_keyframes = 0;
  int num_odometry_factors = 0;
  int num_degenerate_keyframes = 0;
  int num_imu_factors = 0;
  int num_dvl_factors = 0;
  int num_loop_closures = 0;
  int num_map_anchors = 0;
  int num_imu_intervals_skipped = 0;  // IMU gaps
  int num_dvl_intervals_skipped = 0;  // DVL dropouts / no coverage
  size_t num_pseudo_samples = 0;      // Algorithm 1 output
  bool covariance_ok = false;
};

struct RefineResult {
  std::vector<KeyframeEstimate> keyframes;
  // The MAP poses' noise the last pass used (body frame; rotation in body axes), and whether
  // it was estimated from the data (RefineOptions::estimate_map_noise) or given.
  MapPoseNoise map_noise;
  bool map_noise_estimated = false;
  double dvl_scale = 1.0;  // s_d of Eq. (8)
  double dvl_scale_sigma = 0.0;
  Eigen::Quaterniond q_body_dvl = Eigen::Quaterniond::Identity();  // refined T_body_dvl rotation
  // Tangent delta theta of R_body_dvl <- R_body_dvl Exp(delta theta), rad^2.
  Eigen::Matrix3d dvl_rotation_covariance = Eigen::Matrix3d::Zero();
  RefineSummary summary;
  // Each GNSS fix's fate in the last pass (RefineInput::gnss order), and their counts.
  std::vector<GnssFixUse> gnss_use;
  GnssCounts gnss_counts;

  Trajectory trajectory() const;  // refined T_world_body at the keyframe stamps
};

// Runs the batch refinement. Throws std::invalid_argument naming the field and the problem for
// bad input (fewer than 2 keyframes, unsorted or duplicate stamps, non-finite values, a
// measurement whose stamps match no keyframe, an odometry edge between the same keyframe).
RefineResult refine_trajectory(const RefineInput& input, const RefineOptions& options = {});

}  // namespace keel::slam
