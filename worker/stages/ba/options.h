// Options of stage `ba` (`--set ba.<name>=<value>`), read, written and documented by one table
// (options.cc, docs/stage-options.md "ba"). The paper's noise figures are not stage options:
// they live in ba::BaOptions.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "worker/ba/ba_options.h"

namespace keel::pipeline {

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
  // The solver's options: the paper's figures of ba::BaOptions with these options' overrides.
  ba::BaOptions solver_options() const;
};

}  // namespace keel::pipeline
