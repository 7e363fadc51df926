// Stage `map` (seed 000 Sec. VI): the dense inspection map, decoupled from SLAM. Every scan of
// every lidar and sonar is streamed through MapBuilder (deskew with the TF tree, the filters of
// Table IV, intermediary maps of N_I scans, final filters) with poses from the chain of
// Sec. VI-C: keyframe poses (`trajectory_refined.tum` of an earlier `refine` stage, else the
// recorded `map` poses) correcting the recorded high-rate `odometry` by Algorithm 2, so every
// scan gets a pose. The first lidar's keyframe scans also build the SLAM-map baseline, and the
// report compares both maps by the metrics of Eqs. (23)-(26), as Table V does.
//
// Artifacts: map_<sensor>.drc / .ply / tiles_<sensor>.tar per sensor, and the same for the
// combined map (Eq. (21), each point with its `sensor`). The maps are kept out of core, in tiles
// within map.memory_budget_mb (tiled_maps.h); a map too large for the budget has no single
// Draco file. Each .drc has its sidecar map_<sensor>.json, and a map larger than
// preview_max_points map_<sensor>_preview.drc with its own sidecar (map_outputs.h).
#pragma once

#include <nlohmann/json.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "worker/mapping/map_builder.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {

// The smallest map.memory_budget_mb accepted: the spill store's buffers and one tile per
// thread need a few MiB each; a dense map may need more (refused naming the minimum).
inline constexpr int kMinMemoryBudgetMb = 64;

// `--set map.<name>=<value>`.
struct MapStageOptions {
  // Scan sensors to map; empty = every lidar and sonar of the mission (sensors riding a servo
  // tray are then skipped and reported, see map_stage.cc).
  std::vector<std::string> sensors;
  // Per sensor type, then per sensor name: mapping::sensor_map_options_from_json objects
  // ({"scan_filters": [...], "intermediary_filters": [...], "final_filters": [...],
  // "deskew": bool}); each key given replaces that part of the defaults below.
  nlohmann::json lidar_filters = nlohmann::json::object();
  nlohmann::json sonar_filters = nlohmann::json::object();
  nlohmann::json sensor_filters = nlohmann::json::object();  // {"<sensor>": {...}}
  // Stage-3 voxel leaf added to every default chain (0: none, Table IV exactly). Without a
  // final voxel grid the map (and memory) grows with the mission; with it, memory grows with
  // the surveyed structure (MapBuilder accumulates voxel sums).
  double final_voxel_leaf_m = 0.02;
  // Merge radius of every streamed final voxel grid, in leaves (mapping::VoxelAccumulator): a
  // point landing in an empty voxel joins an occupied neighbour whose centroid lies within the
  // radius. It makes the map (and memory) saturate on the surveyed structure instead of growing
  // as a slower survey fills more voxels of the range-noise shell. 0: plain voxel grid. Off by
  // default: on the keel-sim bridge one leaf does not reach the 1.5x memory target and costs
  // density and roughness (docs/map-filters.md, "Throughput and memory").
  double final_voxel_merge_radius_leaves = 0.0;
  int scans_per_intermediary = 10;  // N_I of Eq. (22)
  bool deskew = true;
  double max_sweep_duration_s = 1.0;
  bool odometry_correction = true;  // Algorithm 2 when the mission records `odometry`

  // Draco: 18 bits keep the quantization error <= sqrt(3)/2 * 200 m / (2^18 - 1) = 0.66 mm
  // on a 200 m map (<= 1 mm up to a 302 m extent).
  int draco_position_bits = 18;
  // 1 rather than 5 or 7: levels 0-1 code the kd-tree's bits directly, 2 and above through
  // rANS. On the 220 s bridge the files grow by 0.15 % (combined map 48.56 vs 48.49 MB: its
  // lossless float intensity is most of the bytes) while the whole stage runs 3 % faster
  // (13.35 vs 13.79 s, median of 4 paired runs) and draco_decoder reads the combined map 18 %
  // faster (what the viewer and `keel fetch` users pay); 5 had saved 25 % of 7's CPU for files
  // 1 % larger. 0 is Draco's sequential encoding: files 18-49 % larger (docs/map-filters.md).
  int draco_compression_level = 1;
  bool write_ply = true;
  // Density, roughness and planarity (Eqs. (23)-(26)) of every point of every map, stored as
  // the Draco attributes "density", "roughness" and "planarity" for a viewer to colour by (where
  // undefined, the value the sidecar gives as the attribute's no_data). Every point is then a query
  // point: on a 2 cm map that costs far more than the sampled metrics of Table V
  // (metrics_max_points), hence off by default.
  bool write_point_metrics = false;
  // A map larger than this also gets map_<sensor>_preview.drc, an even thinning to this many
  // points that a viewer opens first (software WebGL draws ~2 M points in about a second);
  // 0: none. Default: none when the maps are written as level-of-detail tiles (write_tiles,
  // the default: the viewer opens a big map from its coarsest tiles; a preview costs a quarter
  // of the stage's output time on the 220 s bridge), else kDefaultPreviewPoints.
  static constexpr size_t kDefaultPreviewPoints = 2000000;
  size_t preview_max_points = 0;

  // Table V metrics (Eqs. (23)-(26)).
  double metrics_radius_m = 0.25;
  // Query points per map, strided evenly over it (neighbours always come from the whole map);
  // 0 = every point. The report gives distributions (mean, percentiles, histogram), which a
  // sample of 20000 points estimates to within ~0.7 % of a standard deviation (standard error
  // std / sqrt(20000)), at a small fraction of the cost of every point of a 2 cm map
  // (~1600 neighbours each within 0.25 m).
  size_t metrics_max_points = 20000;
  // SLAM-map baseline: the keyframe scans of `slam_sensor` (empty = the first lidar mapped).
  std::string slam_sensor;
  double slam_keyframe_leaf_m = 0.2;
  int threads = 2;
  // Memory the stage keeps its maps within (MiB, issue 17): what leaves the scans is kept in
  // spatial tiles that spill to disk beyond a quarter of it, filtered and read a tile at a
  // time (a quarter, shared by the threads), and half is left to the output tasks: a map's
  // single Draco file is written only when encoding it fits there (~64 bytes per point).
  int memory_budget_mb = 2048;
  // Also write each map as level-of-detail tiles (tiles_<map>.tar, docs/artifacts.md).
  bool write_tiles = true;

  // Fails (ContractError) naming the option, and listing the known ones for an unknown name.
  static MapStageOptions from_json(const nlohmann::json& options);
  nlohmann::json to_json() const;
  // The defaults of a sensor of type "lidar" or "sonar" (Table IV scan filters, the final
  // voxel grid, deskew), then `lidar_filters`/`sonar_filters`, then `sensor_filters[sensor]`.
  mapping::SensorMapOptions sensor_options(const std::string& sensor,
                                           const std::string& type) const;
};

}  // namespace keel::pipeline
