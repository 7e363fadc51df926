// Stage `ba` (seed 001, Sec. 2 and the comparison of Sec. 4): model-assisted bundle
// adjustment of a hull mission against its CAD mesh (worker/ba/model_assisted_ba.h).
//
// Keyframes are the camera's images; their initial poses are the recorded `map` keyframe poses
// correcting the recorded `odometry` (Algorithm 2 of seed 000, as the map stage does), the
// servo angle and pressure depth are interpolated at each image, and the DVL range sample
// nearest to each image (within `dvl_max_dt_s`) becomes that keyframe's Eq. (14) returns.
// Feature tracks come from the SIFT frontend on the images (`tracks=frontend`, default) or from
// the simulator's ground-truth tracks listed in truth.yaml (`tracks=ground_truth`).
//
// Artifacts: `trajectory_ba.tum` (keyframe poses of the `proposed` mode, else of the last mode
// run) and `ba_solution.json` (that mode's landmarks, camera poses and x_gM, which the
// `inspect` stage reads); that mode's trajectory in the model frame added to
// `trajectories.json` as `ba`; `cad_model.drc` (+ sidecar `cad_model.json`). The report has one
// section per mode: iterations, time, cost, the lambda = 1 fraction per iteration (Fig. 16), the
// DVL range residuals after GICP alone and after the mode (Fig. 18), and x_gM against truth.yaml's
// T_world_cad when present.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

#include "worker/ba/ba_options.h"
#include "core/pose.h"
#include "worker/pipeline/stage.h"
#include "worker/pipeline/pose_json.h"
#include "worker/stages/ba/artifacts.h"

namespace keel::pipeline {

// `--set ba.<name>=<value>`.
struct BaStageOptions {
  std::string mode = "all";         // proposed | geva | naive | all (Sec. 4 compares all three)
  std::string tracks = "frontend";  // frontend | ground_truth (truth.yaml feature_tracks)
  // Sensors: empty = the first sensor of that type in mission.yaml.
  std::string camera_sensor;
  std::string dvl_ranges_sensor;
  std::string servo_sensor;
  std::string depth_sensor;
  bool use_depth = true;       // Eq. (9) z from the pressure sensor (else off the initial pose)
  double dvl_max_dt_s = 0.05;  // a DVL ping further than this from every image is not used
  // Servo angle at an image: a line fitted to the samples in this window (0: interpolation).
  double servo_window_s = 1.0;
  // Initial landmarks: tracks reprojecting further than this from the initial poses are
  // dropped (keel::ba::TriangulationOptions). Its 20 px kept 18 of 307 tracks on keel-sim
  // hauv-hull (MAP poses ~5 cm off, servo angles 5 deg noisy at 1.5 m standoff); 80 px kept all.
  double triangulation_max_reprojection_px = 80.0;
  int max_keyframes = 0;  // 0 = every image; else the first N (short test runs)
  // Solver figures passed through to keel::ba::BaOptions (paper defaults there).
  int max_iterations = 100;
  // Ceres stops when an iteration lowers the cost by less than this fraction of it (Ceres's
  // default). On keel-sim hauv-hull every solve is within 1e-4 of its final cost by iteration
  // 6-7; the last 1-3 iterations each gain ~2e-6 (docs/stage-options.md).
  double function_tolerance = 1e-6;
  int threads = 2;
  std::string linear_solver = "sparse_schur";
  std::string dvl_range_normal = "interpolated";  // | "facet" (ba::DvlRangeNormal)
  // Fig. 18 histogram of DVL range residuals: bins of this width over [-range, +range].
  double histogram_bin_m = 0.005;
  double histogram_range_m = 0.05;
  // cad_model.drc: 16 bits keep the quantization error <= sqrt(3)/2 * 30 m / (2^16 - 1) = 0.4 mm
  // on a 30 m hull (as inspect's mesh_remeshed.drc).
  int cad_draco_position_bits = 16;

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static BaStageOptions from_json(const nlohmann::json& options);
  std::vector<ba::BaMode> modes() const;
};

// A residual distribution as the report gives it (Fig. 18): count, mean, sigma (the standard
// deviation), robust_sigma (1.4826 x the median absolute deviation from the median), the 5/25/
// 50/75/95 percentiles and a histogram over +-histogram_range_m in histogram_bin_m bins.
nlohmann::json residual_stats(std::vector<double> residuals_m, const BaStageOptions& options);

// An estimated model pose against the truth (the report's `T_world_model_vs_truth`): the
// translation error's norm and its components along the true model frame's axes, m, and the
// rotation angle between them, degrees.
nlohmann::json model_error(const Pose3& estimate, const Pose3& truth);

}  // namespace keel::pipeline
