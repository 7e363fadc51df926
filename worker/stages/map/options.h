// The `map` stage's options (`--set map.<name>=<value>`): the struct with its defaults, and the
// table (options.cc) that reads, writes and documents them (docs/stage-options.md, `map`).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "worker/mapping/map_builder.h"
#include "worker/pipeline/option_table.h"

namespace keel::pipeline {

// The smallest map.memory_budget_mb accepted: the spill store's buffers and one tile per
// thread need a few MiB each; a dense map may need more (refused naming the minimum).
inline constexpr int kMinMemoryBudgetMb = 64;

struct MapStageOptions {
  // Scan sensors to map; empty = every lidar and sonar of the mission.
  std::vector<std::string> sensors;
  // mapping::sensor_map_options_from_json objects ({"scan_filters": [...],
  // "intermediary_filters": [...], "final_filters": [...], "deskew": bool}) per sensor type,
  // then per sensor name; each key given replaces that part of the defaults (sensor_options).
  nlohmann::json lidar_filters = nlohmann::json::object();
  nlohmann::json sonar_filters = nlohmann::json::object();
  nlohmann::json sensor_filters = nlohmann::json::object();  // {"<sensor>": {...}}
  // Stage-3 voxel leaf added to every default chain (0: none, Table IV exactly). Without a
  // final voxel grid the map (and memory) grows with the mission; with it, with the surveyed
  // structure (MapBuilder accumulates voxel sums).
  double final_voxel_leaf_m = 0.02;
  // Merge radius of every streamed final voxel grid, in leaves (mapping::VoxelAccumulator).
  // Off: on the keel-sim bridge one leaf costs density and roughness without reaching the
  // memory target (docs/map-filters.md, "Merge rule").
  double final_voxel_merge_radius_leaves = 0.0;
  int scans_per_intermediary = 10;  // N_I of Eq. (22)
  bool deskew = true;
  double max_sweep_duration_s = 1.0;
  bool odometry_correction = true;  // Algorithm 2 when the mission records `odometry`

  // Draco: 18 bits keep the quantization error <= sqrt(3)/2 * 200 m / (2^18 - 1) = 0.66 mm
  // on a 200 m map (<= 1 mm up to a 302 m extent).
  int draco_position_bits = 18;
  // 1: levels 0-1 code the kd-tree's bits directly, 2 and above through rANS, which costs
  // more CPU to write and to read for files barely smaller (the map's lossless intensity is
  // most of the bytes); 0, Draco's sequential encoding, makes files much larger.
  int draco_compression_level = 1;
  bool write_ply = true;
  // Density, roughness and planarity of every point as Draco attributes: every point is then
  // a query point, far costlier than the sampled metrics of Table V, hence off.
  bool write_point_metrics = false;
  // Points of a map's preview, 0 for none. None while the maps are written as level-of-detail
  // tiles (the viewer opens a big map from its coarsest tiles), else kDefaultPreviewPoints
  // (software WebGL draws ~2 M points in about a second): the `write_tiles` row sets it.
  static constexpr size_t kDefaultPreviewPoints = 2000000;
  size_t preview_max_points = 0;

  // Table V metrics (Eqs. (23)-(26)).
  double metrics_radius_m = 0.25;
  // Query points per map: a sample of 20000 estimates the reported distributions to within
  // ~0.7 % of a standard deviation (std / sqrt(20000)), at a small fraction of every point.
  size_t metrics_max_points = 20000;
  // SLAM-map baseline: the keyframe scans of `slam_sensor` (empty = the first lidar mapped).
  std::string slam_sensor;
  double slam_keyframe_leaf_m = 0.2;
  int threads = 2;
  // MiB the stage keeps its maps within (issue 17; shares in tiled_maps.h).
  int memory_budget_mb = 2048;
  bool write_tiles = true;  // tiles_<map>.tar, docs/artifacts.md

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static MapStageOptions from_json(const nlohmann::json& options);
  nlohmann::json to_json() const;
  // The defaults of a sensor of type "lidar" or "sonar" (Table IV scan filters, the final
  // voxel grid, deskew), then `lidar_filters`/`sonar_filters`, then `sensor_filters[sensor]`.
  mapping::SensorMapOptions sensor_options(const std::string& sensor,
                                           const std::string& type) const;
};

const OptionTable<MapStageOptions>& map_option_table();

class TileBudgetError;  // tiled_maps.h
// A memory_budget_mb that cannot hold one tile: ContractError naming the option and the
// smallest budget that would work.
[[noreturn]] void throw_memory_budget_error(const TileBudgetError& error,
                                            const MapStageOptions& options);

}  // namespace keel::pipeline
