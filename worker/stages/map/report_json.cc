#include "worker/stages/map/report_json.h"

#include <algorithm>
#include <fstream>
#include <utility>

#include "worker/stages/map/output_runner.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

double peak_rss_mib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  return 0.0;
}

json filter_steps_json(const mapping::StageStats& stage) {
  json steps = json::array();
  for (const auto& step : stage.steps)
    steps.push_back(
        {{"filter", step.filter}, {"points_in", step.points_in}, {"points_out", step.points_out}});
  return {{"applications", stage.applications}, {"filters", steps}};
}

json stats_json(const mapping::SensorMapStats& s) {
  return {{"scans", s.scans},
          {"scans_outside_trajectory", s.scans_outside_trajectory},
          {"points_in", s.points_in},
          {"non_finite_points", s.non_finite_points},
          {"intermediary_maps", s.intermediary_maps},
          {"scan_stage", filter_steps_json(s.scan_stage)},
          {"intermediary_stage", filter_steps_json(s.intermediary_stage)},
          {"final_stage", filter_steps_json(s.final_stage)},
          {"points_out", s.points_out}};
}

json filter_tiles_json(const TiledFilterStats& t) {
  return {{"filter_tiles", t.tiles},
          {"splits", t.splits},
          {"halo_points", t.halo_points},
          {"largest_tile_points", t.largest_tile_points}};
}

// The filter that removed every remaining point (a DROR whose alpha_deg does not match the
// sensor's angular resolution, typically), or "" when the map kept points.
std::string emptied_by(const mapping::SensorMapStats& s) {
  const std::pair<const char*, const mapping::StageStats*> stages[] = {
      {"scan", &s.scan_stage}, {"intermediary", &s.intermediary_stage}, {"final", &s.final_stage}};
  for (const auto& [stage, stats] : stages)
    for (const auto& step : stats->steps)
      if (step.points_in > 0 && step.points_out == 0)
        return std::string(stage) + "-stage filter '" + step.filter + "' removed all " +
               std::to_string(step.points_in) +
               " points (check its parameters against the sensor, e.g. DROR's alpha_deg)";
  return "";
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

void reset_peak_rss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
}

json describe_sensors(const SensorSelection& selection, const ScanPass& scans, json& warnings) {
  const std::vector<std::string> built = scans.built();
  json sensors = json::object();
  for (const auto& s : selection.mapped) {
    json entry = {{"type", s.type}, {"filters", mapping::to_json(scans.sensor_options(s.name))}};
    if (!contains(built, s.name)) {
      entry["stats"] = nullptr;
      warnings.push_back("sensor '" + s.name + "': no scans");
      sensors[s.name] = entry;
      continue;
    }
    const mapping::SensorMapStats stats = scans.sensor_stats(s.name);
    entry["stats"] = stats_json(stats);
    entry["tiles"] = filter_tiles_json(scans.tiled().filter_stats(s.name));
    if (scans.map_points(s.name) == 0)
      warnings.push_back("sensor '" + s.name + "': the map is empty (every point filtered, " +
                         "or every scan outside the trajectory); no artifacts written");
    if (stats.scans_outside_trajectory > 0)
      warnings.push_back("sensor '" + s.name +
                         "': " + std::to_string(stats.scans_outside_trajectory) +
                         " scans outside the trajectory were skipped");
    if (const std::string w = emptied_by(stats); !w.empty())
      warnings.push_back("sensor '" + s.name + "': " + w);
    sensors[s.name] = entry;
  }
  return sensors;
}

std::vector<std::string> written_sensor_maps(const SensorSelection& selection,
                                             const ScanPass& scans) {
  const std::vector<std::string> built = scans.built();
  std::vector<std::string> written;
  for (const auto& s : selection.mapped)
    if (contains(built, s.name) && scans.map_points(s.name) > 0) written.push_back(s.name);
  std::stable_sort(written.begin(), written.end(), [&](const std::string& a, const std::string& b) {
    return scans.map_points(a) > scans.map_points(b);
  });
  return written;
}

json describe_slam_map(const ScanPass& scans, const MapStageOptions& options, json& warnings) {
  if (!scans.slam()) {
    warnings.push_back("no lidar mapped: no SLAM-map baseline");
    return nullptr;
  }
  if (scans.slam_points() == 0)
    warnings.push_back("SLAM map: no scan of '" + scans.slam_sensor()->name +
                       "' matches a keyframe; no baseline");
  return {{"sensor", scans.slam_sensor()->name},
          {"keyframes", scans.slam()->keyframes()},
          {"keyframes_used", scans.slam()->keyframes_used()},
          {"keyframe_leaf_m", options.slam_keyframe_leaf_m},
          {"points", scans.slam_points()}};
}

json timing_report(const MapTimes& t, int threads) {
  const double stage_seconds = seconds_since(t.stage_start);
  const double points_in = static_cast<double>(t.input_points);
  return {{"stage_seconds", stage_seconds},
          {"stage_input_points_per_second", stage_seconds > 0 ? points_in / stage_seconds : 0.0},
          {"outputs_and_metrics_seconds", seconds_since(t.outputs_start)},
          {"threads", threads},
          {"scans_seconds", t.scans_seconds},
          {"input_points", t.input_points},
          {"input_points_per_second", t.scans_seconds > 0 ? points_in / t.scans_seconds : 0.0},
          {"metrics_seconds", t.metrics_seconds},
          {"metrics_query_points_per_second",
           t.metrics_seconds > 0 ? t.metrics_query_points / t.metrics_seconds : 0.0}};
}

json memory_report(const MapStageOptions& options, const TiledMaps& tiled,
                   double output_budget_bytes) {
  const io::SpillStore& store = tiled.store();
  const double mib = 1 << 20;
  return {{"budget_mb", options.memory_budget_mb},
          {"peak_rss_mib", peak_rss_mib()},
          {"spill_buffer_budget_mib", static_cast<double>(store.buffer_budget()) / mib},
          {"spill_buffered_peak_mib", static_cast<double>(store.peak_bytes_buffered()) / mib},
          {"bytes_spilled", store.bytes_spilled()},
          {"tile_budget_mib", static_cast<double>(tiled.options().tile_budget_bytes) / mib},
          {"output_budget_mib", output_budget_bytes / mib}};
}

}  // namespace keel::pipeline
