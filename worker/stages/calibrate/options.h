// The `calibrate` stage's options (`--set calibrate.<name>=<value>`): the struct with its
// defaults, and the table (options.cc) that reads, writes and documents them
// (docs/stage-options.md, `calibrate`).
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

#include "worker/mapping/extrinsic_refinement.h"
#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

struct CalibrateStageOptions {
  // The sensor the others are calibrated against; empty = the first lidar with scans.
  std::string reference;
  // The sensors to calibrate; empty = every other lidar and sonar with scans that does not
  // ride a servo tray (`mounted_on`: its extrinsic varies with the tray angle).
  std::vector<std::string> candidates;
  // Every keyframe_stride-th keyframe (of the refined trajectory, else the recorded `map`).
  int keyframe_stride = 1;
  double scan_voxel_m = 0.1;  // per-scan voxel leaf of the keyframe scans (and of the file)
  double max_sweep_duration_s = 1.0;
  bool odometry_correction = true;  // Algorithm 2 between keyframes, as `map` does

  // The refinement (mapping::ExtrinsicRefinementOptions).
  std::string loss = "huber";  // "huber" | "cauchy"
  double loss_scale_m = 0.05;
  double max_correspondence_m = 1.0;
  double final_correspondence_m = 0.3;
  // mapping::ExtrinsicRefinementOptions::plane_extrapolation_m for sonar candidates (lidars:
  // 0). A sonar sees under the water and the reference lidar above it; they share the
  // planes that continue across the waterline, not points.
  double sonar_plane_extrapolation_m = 3.0;
  int max_iterations = 30;
  double unobservable_ratio = 1e-2;
  size_t min_overlap_points = 200;
  double min_overlap_fraction = 0.02;
  size_t max_candidate_points = 300000;

  // Table V metrics of the combined reference + candidate cloud (Eqs. (23)-(26)).
  double metrics_radius_m = 0.25;
  size_t metrics_max_points = 20000;
  int threads = 2;

  mapping::ExtrinsicRefinementOptions refinement(const std::string& candidate_type = "") const;
  static CalibrateStageOptions from_json(const nlohmann::json& options);  // options.cc
  nlohmann::ordered_json to_json() const;
};

const OptionTable<CalibrateStageOptions>& calibrate_option_table();

}  // namespace keel::pipeline
