// Steps 3 and 4 of the map stage: every scan of every sensor through a MapBuilder of its own
// (seed 000 Fig. 5: a sensor's map depends on its own scans only, so a sensor's outputs can
// start once its last scan is in), `threads` scans at a time and committed in order
// (MapBuilder::add_scans), on the TF tree W -> B -> S_i of the poses and extrinsics; the SLAM
// lidar's scans also through SlamMapBuilder for the SLAM-map baseline. The maps are kept out
// of core (tiled_maps.h): what leaves a sensor's intermediary stage goes to its tiles, and
// once its last scan is in its final filters run tile by tile. With the merge rule, which
// depends on the order of the whole stream, the builder runs the final chain and the tiles
// hold its result.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "worker/io/mission_reader.h"
#include "worker/mapping/map_builder.h"
#include "worker/mapping/slam_map.h"
#include "worker/mapping/transform_tree.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/map/options.h"
#include "worker/pipeline/body_poses.h"
#include "worker/stages/map/sensors.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

// Progress: the scans take [0, kScansDone], the outputs and metrics the rest.
inline constexpr double kScansDone = 0.75;

class ScanPass {
 public:
  // The TF tree, one MapBuilder per sensor, the SLAM-map baseline (when a lidar is mapped) and
  // the tiles, whose spill file goes to `work_dir`. The arguments must outlive the pass.
  ScanPass(const MapStageOptions& options, const SensorSelection& selection, const Poses& poses,
           const std::filesystem::path& work_dir);
  ScanPass(const ScanPass&) = delete;
  ScanPass& operator=(const ScanPass&) = delete;

  // Opens every sensor's scans; returns how many there are (index.csv or the bag).
  size_t open_scans(const io::MissionReader& reader);
  // Streams the scans of selection.mapped[k] through its builder (and the baseline).
  void scan_sensor(size_t k, const StageContext& context);
  // That sensor's map is complete: its final filters over its tiles; the SLAM lidar's also
  // completes the SLAM map. Throws ContractError naming memory_budget_mb for a tile too dense.
  void finish_sensor(size_t k, const StageContext& context);

  const SensorSelection& selection() const { return selection_; }
  bool has_scans(const std::string& sensor) const;
  std::vector<std::string> built() const;  // sensors that had scans, in name order
  size_t input_points() const;             // points of their scans
  TiledMaps& tiled() { return *tiled_; }
  const TiledMaps& tiled() const { return *tiled_; }
  size_t map_points(const std::string& map) const { return tiled_->points(map); }
  // The builder's counts, the final stage as the tiles ran it (the whole map's counts).
  mapping::SensorMapStats sensor_stats(const std::string& sensor) const;
  const mapping::SensorMapOptions& sensor_options(const std::string& sensor) const;
  // The baseline's lidar and builder; null without a lidar mapped.
  const MappedSensor* slam_sensor() const { return slam_sensor_; }
  const mapping::SlamMapBuilder* slam() const { return slam_ ? &*slam_ : nullptr; }
  size_t slam_points() const { return slam_points_; }

 private:
  bool merging() const { return options_.final_voxel_merge_radius_leaves > 0.0; }

  const MapStageOptions& options_;
  const SensorSelection& selection_;
  mapping::TransformTree tree_;  // the builders and the baseline read it
  mapping::MapBuilderOptions builder_options_;
  std::unique_ptr<TiledMaps> tiled_;
  std::map<std::string, std::unique_ptr<mapping::MapBuilder>> builders_;
  const MappedSensor* slam_sensor_ = nullptr;  // in selection_.mapped
  std::optional<mapping::SlamMapBuilder> slam_;
  size_t slam_points_ = 0;
  std::vector<std::unique_ptr<io::ScanSource>> sources_;  // by sensor, until scanned
  size_t total_scans_ = 0, scans_done_ = 0;
};

}  // namespace keel::pipeline
