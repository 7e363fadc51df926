// The map stage's metrics (seed 000 Eqs. (23)-(26)) and its Table V: the mean surface
// density, roughness and planarity of the SLAM map and of the inspection maps, each measured
// from its tiles, and how the inspection map changes the SLAM map's.
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "worker/mapping/map_metrics.h"
#include "worker/stages/map/options.h"
#include "worker/stages/map/sensors.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

struct MetricsColumn {
  std::string name;  // "slam_map", "inspection_<sensor>", "inspection_combined"
  mapping::MapMetrics metrics;
  double seconds = 0.0;
};

// Table V's columns, each measured by an output task (output_plan.h).
struct MetricsColumns {
  std::optional<MetricsColumn> slam_map, inspection, combined;
};

mapping::MapMetricsOptions map_metrics_options(const MapStageOptions& options,
                                               std::function<void()> check_canceled);

// The metrics of the map made of `parts` (TiledMaps' maps), from its tiles.
MetricsColumn measure_tiled(const std::string& name, TiledMaps& tiled,
                            const std::vector<std::string>& parts, const MapStageOptions& options,
                            std::function<void()> check_canceled);

// Table V's inspection map: the SLAM lidar's own map when it was written (the same sensor as
// the baseline), else the combined map.
std::string inspection_map_name(const MappedSensor* slam_sensor,
                                const std::vector<std::string>& written);

// report.json's map.metrics: each map's metrics and Table V, with `inspection_map` compared
// with the SLAM map. Adds the columns' seconds and query points to the totals.
nlohmann::json metrics_report(const MetricsColumns& columns, const std::string& inspection_map,
                              const MapStageOptions& options, double& seconds,
                              size_t& query_points);

}  // namespace keel::pipeline
