// MapBuilder, seed 000 Sec. VI-A (Fig. 5), as a streaming class. Scans are fed one at a time;
// each is (1) cleared of non-finite points, (2) motion-compensated with the TF tree,
// (3) filtered in its sensor frame (stage 1), (4) transformed into W (Eq. (20) -> W V_{WS_i,K_j}),
// (5) gathered with the next scans of its sensor into an intermediary map of N_I scans
// (Eq. (22)), filtered (stage 2) and appended to the sensor's map; finish() flushes the last,
// partial intermediary map and filters each sensor's map (stage 3). The union over sensors is
// Eq. (21).
//
// Memory: raw scans are never kept beyond one intermediary batch per sensor. When a sensor's
// final filters start with a voxel grid, its map is accumulated as running voxel sums
// (VoxelAccumulator, identical to voxelizing the whole map at the end, or with the merge rule
// that makes the map saturate on the structure), so memory grows with the output map, not
// with mission length.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/mapping/deskew.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/transform_tree.h"

namespace keel::mapping {

struct SensorMapOptions {
  FilterChain scan_filters = table_iv_lidar_scan_filters();  // stage 1, sensor frame
  FilterChain intermediary_filters;                          // stage 2, world frame
  FilterChain final_filters;                                 // stage 3, world frame
  bool deskew = true;  // only scans with per-point times are deskewed
};

// Reads {"scan_filters": [...], "intermediary_filters": [...], "final_filters": [...],
// "deskew": true} (each key optional, the others keep `defaults`). Throws
// std::invalid_argument naming `where` and the key for anything malformed or unknown.
SensorMapOptions sensor_map_options_from_json(const nlohmann::json& json, const std::string& where,
                                              SensorMapOptions defaults = {});
nlohmann::json to_json(const SensorMapOptions& options);

struct MapBuilderOptions {
  // N_I, the number of scans per intermediary map (Eq. (22)); the paper gives no value. Ten
  // VLP-16 sweeps (1 s) make an intermediary map dense enough for ROR to separate inliers.
  int scans_per_intermediary = 10;
  std::map<std::string, SensorMapOptions> sensors;  // per sensor name
  SensorMapOptions default_sensor;                  // for sensors not listed
  DeskewOptions deskew;
  // Scans whose stamp or point times fall outside the trajectory (a sensor started before the
  // SLAM system): true skips and counts them, false makes add_scan throw std::out_of_range.
  bool skip_scans_outside_trajectory = true;
  // Merge radius of a streamed final voxel grid, in leaves (VoxelAccumulator's merge rule: a
  // point landing in an empty voxel joins an occupied neighbour whose centroid is within the
  // radius). 0 keeps the plain voxel grid of the paper, whose map keeps growing with sampling
  // density inside the range-noise shell; > 0 makes it saturate on the structure. At most
  // VoxelAccumulator::kMaxMergeLeaves.
  double final_voxel_merge_radius_leaves = 0.0;
  int threads = 2;
  // When set, each intermediary map, filtered, goes here (in feed order, from the committing
  // thread) instead of into the sensor's map: the final filters then run elsewhere (the map
  // stage's tiles, out of core), and sensor_map() stays empty.
  std::function<void(const std::string& sensor, const PointCloud& points)> final_sink;
};

// Per-filter counts of one stage, summed over every application (same order as the chain).
struct StageStats {
  size_t applications = 0;
  std::vector<FilterStep> steps;
};

struct SensorMapStats {
  size_t scans = 0;                     // fed to add_scan
  size_t scans_outside_trajectory = 0;  // skipped
  size_t points_in = 0;                 // of the scans fed
  size_t non_finite_points = 0;         // removed before anything else
  size_t intermediary_maps = 0;         // including the last, partial one
  StageStats scan_stage, intermediary_stage, final_stage;
  size_t points_out = 0;  // in the sensor's final map
};

class MapBuilder {
 public:
  // Throws std::invalid_argument for N_I < 1 or a DROR filter outside stage 1 (DROR measures
  // range from the scan origin, which a world-frame map no longer has).
  MapBuilder(const TransformTree& tree, MapBuilderOptions options);
  ~MapBuilder();
  MapBuilder(const MapBuilder&) = delete;
  MapBuilder& operator=(const MapBuilder&) = delete;

  // `scan` in the sensor frame, t_ns its stamp, time_s (optional) per-point offsets in s.
  void add_scan(const std::string& sensor, PointCloud scan);
  // Fills `sensor` and `scan` with the next scan, or returns false after the last one.
  using ScanFeed = std::function<bool(std::string& sensor, PointCloud& scan)>;
  // add_scan for every scan `next` yields, on options.threads threads: each thread takes the
  // next scan from the feed (calls to `next` never overlap and follow feed order), deskews,
  // filters and transforms it on its own, and then commits it to its sensor's map in feed
  // order, so the result equals add_scan called scan by scan. An exception from `next` or
  // from any scan stops every thread and is rethrown here.
  void add_scans(const ScanFeed& next);
  // Flushes partial intermediary maps and applies the final filters; add_scan after it throws.
  void finish();

  std::vector<std::string> sensors() const;
  // The sensor's map in W (after finish()). Throws naming an unknown sensor.
  const PointCloud& sensor_map(const std::string& sensor) const;
  const SensorMapStats& stats(const std::string& sensor) const;
  // Eq. (21): the union of every sensor's map (intensity kept when all carry it).
  PointCloud combined_map() const;

 private:
  struct SensorState;
  struct PreparedScan;
  SensorState& state_for(const std::string& sensor);
  const SensorState& existing_state(const std::string& sensor) const;
  // add_scan in two halves: per-scan work that touches no shared state (any thread) ...
  PreparedScan prepare(const std::string& sensor, SensorState& state, PointCloud scan,
                       int filter_threads) const;
  // ... and the part that extends the sensor's map (in scan order).
  void commit(PreparedScan prepared);
  void flush_intermediary(SensorState& state);

  const TransformTree& tree_;
  MapBuilderOptions options_;
  std::map<std::string, std::unique_ptr<SensorState>> states_;
  bool finished_ = false;
};

}  // namespace keel::mapping
