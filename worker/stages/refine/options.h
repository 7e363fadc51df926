// Options of stage `refine` (`--set refine.<name>=<value>`), read, written and documented by
// one table (options.cc, docs/stage-options.md "refine"). Defaults are seed 000's; the sensor
// noise figures of Table I are not options but each sensor's `noise` in mission.yaml.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

#include "worker/slam/refine_solver.h"
#include "worker/slam/relative_pose.h"

namespace keel::pipeline {

struct RefineStageOptions {
  // Sensors: empty = the first sensor of that type in mission.yaml.
  std::string imu_sensor;
  std::string dvl_sensor;
  std::string lidar_sensor;  // scans for GICP odometry when the mission records none

  bool dvl = true;                 // DVL fusion; false refines with odometry, loops and IMU only
  bool estimate_dvl_scale = true;  // s_d of Eq. (8) as a state (Sec. VII)
  double dvl_scale_initial = 1.0;  // also the held value when not estimated
  double dvl_scale_prior_sigma = 0.1;
  bool estimate_dvl_rotation = true;            // DVL-IMU extrinsic rotation as a state (Sec. VII)
  double dvl_rotation_prior_sigma_deg = 2.865;  // 0.05 rad
  double max_dvl_gap_s = 0.5;                   // Algorithm 1: dropouts longer are not bridged
  // A DVL on a servo tray: its velocities are turned into its angle-0 frame with the tray angle
  // of a line fitted to the servo samples within this window, s (as ba's servo_window_s).
  double servo_window_s = 1.0;

  std::string odometry = "auto";  // auto (recorded, else gicp) | recorded | gicp
  bool loop_closures = true;
  // Recorded odometry carries no covariance: sigma = base + per_metre * |t_ij| (relative_pose.h);
  // options odometry_sigma_translation_m, _translation_per_m, _rotation_rad, _rotation_per_rad.
  slam::OdometryNoise recorded_odometry_noise;
  // Beyond the paper: widen the odometry sigmas per axis by the RMS disagreement between the
  // odometry increments and the MAP poses' increments (slam/odometry_noise_from_map.h), so an
  // odometry that degenerated (a corridor) stops outvoting the DVL. false: the fixed model above.
  bool odometry_noise_from_map = true;
  std::string degeneracy = "drop";  // drop (seed 000) | keep_well_conditioned | ignore
  // An odometry direction is degenerate when its sigma (after the widening above) exceeds this:
  // 0.2 m is a fifth of a ~1 m keyframe step, far beyond a working lidar odometry (~1 % of
  // distance) and far below what a corridor's lost axis shows (slam::DegeneracyOptions).
  double degeneracy_sigma_translation_m = 0.2;
  double degeneracy_sigma_rotation_rad = 0.1;
  // Over degenerate intervals keep the IMU factor's position residual next to the DVL factor
  // (slam::RefineOptions::imu_position_when_degenerate); false: seed 000's rule everywhere.
  bool imu_position_when_degenerate = true;
  // Beyond the paper: offline, the global constraints of the online SLAM (scan-to-map matching,
  // its loop closures) survive only in its MAP poses, so each keyframe is anchored to its MAP
  // pose (slam::RefineOptions::use_map_anchors: white noise plus a drift over the degenerate
  // stretches, Huber-robustified). Without them nothing bounds the heading drift of odometry +
  // IMU + DVL dead reckoning.
  bool map_anchors = true;
  double map_sigma_translation_m = 0.05;
  double map_sigma_rotation_rad = 0.01;
  // The MAP poses' noise (slam::MapPoseNoise): white sigmas above and a drift random walk, m
  // per sqrt(m) of degenerate path; with estimate_map_noise these are the first pass's values
  // and later passes use the noise estimated from the data.
  double map_drift_per_sqrt_m = 0.001;
  bool estimate_map_noise = true;

  // GNSS position factors (issue 30), when the mission has a gnss sensor.
  bool gnss = true;
  std::string gnss_sensor;         // empty: the first gnss sensor
  double gnss_gate_chi2 = 16.266;  // chi-square, 3 dof, p = 0.999
  double gnss_min_sigma_m = 0.02;  // floor on a fix's stated sigma (RTK fixes claim mm)

  int max_iterations = 50;
  int relinearization_passes = 2;
  int threads = 2;

  // Evaluation against ground truth (when the mission has it).
  bool compare_without_dvl = true;          // solve a second time without DVL for Table II
  double ate_max_time_difference_s = 0.01;  // evo's --t_max_diff
  double rpe_delta_m = 5.0;                 // RPE pairs every 5 m of ground-truth path

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static RefineStageOptions from_json(const nlohmann::json& options);
  // What report.json echoes as `options`: the main switches and sigmas.
  nlohmann::json report_json() const;
  // The solver options these stand for (sensor noise is filled in from mission.yaml).
  slam::RefineOptions solver_options() const;
};

}  // namespace keel::pipeline
