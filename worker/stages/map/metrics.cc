#include "worker/stages/map/metrics.h"

#include <algorithm>
#include <chrono>

#include "worker/stages/map/output_runner.h"
#include "worker/stages/map/tiled_outputs.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

double mean_of(const mapping::MapMetrics& m, const std::string& metric) {
  if (metric == "surface_density") return m.surface_density.mean;
  if (metric == "roughness") return m.roughness.mean;
  return m.planarity.mean;
}

// Table V of seed 000: the mean of each metric per map, the SLAM map first, and how the
// inspection map (`primary`) changes it: density as a factor, roughness and planarity in %.
json table_v(const std::vector<MetricsColumn>& columns, const std::string& primary) {
  json rows = json::array();
  const char* units[] = {"points/m^2", "m", "1"};
  const char* metrics[] = {"surface_density", "roughness", "planarity"};
  for (int k = 0; k < 3; ++k) {
    json row = {{"metric", metrics[k]}, {"unit", units[k]}};
    for (const auto& c : columns) row[c.name] = mean_of(c.metrics, metrics[k]);
    rows.push_back(row);
  }
  json out = {{"columns", json::array()}, {"rows", rows}, {"inspection_map", primary}};
  for (const auto& c : columns) out["columns"].push_back(c.name);
  const MetricsColumn* slam = nullptr;
  const MetricsColumn* inspection = nullptr;
  for (const auto& c : columns) {
    if (c.name == "slam_map") slam = &c;
    if (c.name == primary) inspection = &c;
  }
  if (!slam || !inspection) return out;
  const auto& s = slam->metrics;
  const auto& i = inspection->metrics;
  auto ratio = [](double a, double b) { return b != 0.0 ? json(a / b) : json(nullptr); };
  auto percent = [](double a, double b) {
    return b != 0.0 ? json(100.0 * (a / b - 1.0)) : json(nullptr);
  };
  out["ratios"] = {{"density_factor", ratio(i.surface_density.mean, s.surface_density.mean)},
                   {"roughness_change_percent", percent(i.roughness.mean, s.roughness.mean)},
                   {"planarity_change_percent", percent(i.planarity.mean, s.planarity.mean)},
                   {"paper_table_v",
                    {{"density_factor", 31986.9 / 337.124},
                     {"roughness_change_percent", 100.0 * (2.576e-2 / 3.637e-2 - 1.0)},
                     {"planarity_change_percent", 100.0 * (6.546e-1 / 4.686e-1 - 1.0)}}}};
  out["inspection_beats_slam"] = {
      {"surface_density", i.surface_density.mean > s.surface_density.mean},
      {"roughness", i.roughness.mean < s.roughness.mean},
      {"planarity", i.planarity.mean > s.planarity.mean}};
  return out;
}

}  // namespace

mapping::MapMetricsOptions map_metrics_options(const MapStageOptions& options,
                                               std::function<void()> check_canceled) {
  mapping::MapMetricsOptions metrics;
  metrics.check_canceled = std::move(check_canceled);
  metrics.radius_m = options.metrics_radius_m;
  metrics.threads = options.threads;
  metrics.max_query_points = options.metrics_max_points;
  return metrics;
}

MetricsColumn measure_tiled(const std::string& name, TiledMaps& tiled,
                            const std::vector<std::string>& parts, const MapStageOptions& options,
                            std::function<void()> check_canceled) {
  const auto start = std::chrono::steady_clock::now();
  MetricsColumn column{name,
                       tiled_map_metrics(tiled, parts, tiled.output_partition(parts),
                                         map_metrics_options(options, std::move(check_canceled))),
                       0.0};
  column.seconds = seconds_since(start);
  return column;
}

std::string inspection_map_name(const MappedSensor* slam_sensor,
                                const std::vector<std::string>& written) {
  if (slam_sensor && std::find(written.begin(), written.end(), slam_sensor->name) != written.end())
    return "inspection_" + slam_sensor->name;
  return "inspection_combined";
}

json metrics_report(const MetricsColumns& measured, const std::string& inspection_map,
                    const MapStageOptions& options, double& seconds, size_t& query_points) {
  std::vector<MetricsColumn> columns;
  for (const auto* column : {&measured.slam_map, &measured.inspection, &measured.combined})
    if (*column) columns.push_back(**column);
  json metrics = {{"radius_m", options.metrics_radius_m},
                  {"max_query_points", options.metrics_max_points},
                  {"maps", json::object()}};
  for (const auto& c : columns) {
    metrics["maps"][c.name] = mapping::to_json(c.metrics);
    metrics["maps"][c.name]["seconds"] = c.seconds;
    seconds += c.seconds;
    query_points += c.metrics.query_points;
  }
  metrics["table_v"] = table_v(columns, inspection_map);
  return metrics;
}

}  // namespace keel::pipeline
