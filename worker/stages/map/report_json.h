// The map stage's report.json sections besides the metrics (metrics.h): what each sensor's
// filters did (Table IV chains), the SLAM-map baseline, the stage's timing and its memory
// against the budget (issue 17), and the warnings that go with them.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <string>
#include <vector>

#include "worker/stages/map/options.h"
#include "worker/stages/map/scan_pass.h"
#include "worker/stages/map/sensors.h"

namespace keel::pipeline {

// The stage's peak RSS is the kernel's high-water mark, reset when the stage starts, so an
// earlier stage of the same process does not count.
void reset_peak_rss();

// map.sensors: each mapped sensor's type, filters, counts and tiles; a warning for a sensor
// without scans, with an empty map, with scans outside the trajectory, or whose filters
// removed every point.
nlohmann::json describe_sensors(const SensorSelection& selection, const ScanPass& scans,
                                nlohmann::json& warnings);
// The sensors whose map has points, largest first (their files are written).
std::vector<std::string> written_sensor_maps(const SensorSelection& selection,
                                             const ScanPass& scans);
// map.slam_map: the baseline's lidar, keyframes and points; null (and a warning) without a
// lidar mapped.
nlohmann::json describe_slam_map(const ScanPass& scans, const MapStageOptions& options,
                                 nlohmann::json& warnings);

struct MapTimes {
  std::chrono::steady_clock::time_point stage_start, outputs_start;
  double scans_seconds = 0.0;
  size_t input_points = 0;
  double metrics_seconds = 0.0;  // the metrics tasks', summed
  size_t metrics_query_points = 0;
};
nlohmann::json timing_report(const MapTimes& times, int threads);

// map.memory: the peak against the budget, what was spilled.
nlohmann::json memory_report(const MapStageOptions& options, const TiledMaps& tiled,
                             double output_budget_bytes);

}  // namespace keel::pipeline
